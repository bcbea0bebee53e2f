#pragma once
// Numbers in text fields (X3P XML, AL3D tags, XYZ lines, CSV cells): locale-independent, whole-field
// parsing (no trailing garbage accepted), and the shortest text that reads back to the same value.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fvm {

// Surrounding blanks (space, tab, CR, LF, NUL) are ignored, a leading '+' is allowed; "nan" and "inf" are read.
std::optional<double> ParseDouble(std::string_view text);
std::optional<std::int64_t> ParseInt(std::string_view text);

std::string_view TrimBlanks(std::string_view text);

// 'A'..'Z' to 'a'..'z' and nothing else, whatever the locale: for matching names (header columns, extensions).
std::string AsciiLower(std::string_view text);

// The words of a line separated by spaces, tabs or CR (header lines of PCD, PLY, XYZ).
std::vector<std::string_view> SplitWords(std::string_view line);

// At most the first 40 characters of `text` in single quotes, for quoting a bad field in a message.
std::string QuotedForMessage(std::string_view text);

// Round-trip exact: ParseDouble(FormatShortest(v)) == v.
std::string FormatShortest(double value);
std::string FormatShortest(float value);

// `value` rounded to the nearest multiple of 1 / per_unit (per_unit 1e4: 0.1 nm in um; 1e7: 0.1 nm in mm), so that
// JSON for scripts keeps 0.1 nm: finer digits are floating-point noise, coarser would throw information away.
// Dividing by the power of ten (not multiplying by its inverse) gives the double that prints as the short decimal.
double RoundTo(double value, double per_unit);

// Fixed notation with `decimals` digits after '.', as printf("%.*f") in the C locale, whatever the locale.
std::string FormatFixed(double value, int decimals);

}  // namespace fvm
