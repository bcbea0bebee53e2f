#pragma once
// Numbers in text fields of surface files (X3P XML, AL3D tags, XYZ lines): locale-independent, whole-field
// parsing (no trailing garbage accepted), and the shortest text that reads back to the same value.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace fvm {

// Surrounding blanks (space, tab, CR, LF, NUL) are ignored, a leading '+' is allowed; "nan" and "inf" are read.
std::optional<double> ParseDouble(std::string_view text);
std::optional<std::int64_t> ParseInt(std::string_view text);

std::string_view TrimBlanks(std::string_view text);

// Round-trip exact: ParseDouble(FormatShortest(v)) == v.
std::string FormatShortest(double value);
std::string FormatShortest(float value);

}  // namespace fvm
