#pragma once
// The numbers an option may take: finite and inside a span that makes physical sense (README, "Option values"),
// checked here, once, for every command. A refusal is a usage error (exit 2) that names the flag, the value and
// the span in readable numbers. `fvm --list-numeric-options` prints every numeric option with its span, so that a
// test tries each one at absurd values and a new flag without a span is caught.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <string_view>

namespace fvm::cli {

// The span of one number: [min, max] in `unit`; a count (`whole`) refuses 2.5 and 1e3 alike as not whole.
struct NumberRange {
  double min = 0.0;
  double max = 0.0;
  std::string unit;
  bool whole = false;

  // Empty when `value` is a finite number inside the span, else why not: "nan is not a finite number",
  // "1e308 mm is outside 0.001 to 100000 mm", "1000.5 is not a whole number". The value is quoted as `written`
  // when given (what the user typed), else in readable digits.
  std::string Refusal(double value, std::string_view written = {}) const;
  std::string Text() const;  // "0.001 to 100000 mm"
};

// Spans shared by many options (mm in files and options, um in reports).
inline const NumberRange kCoordinateMm{-1e5, 1e5, "mm"};  // a position within 100 m of the origin
inline const NumberRange kTravelMm{1e-3, 1e5, "mm"};      // an axis travel or a region's size: 1 um to 100 m
inline const NumberRange kStepMm{1e-3, 1e5, "mm"};        // a grid step or a path's length
inline const NumberRange kAngleDeg{-360.0, 360.0, "deg"};
inline const NumberRange kPixelMm{1e-6, 10.0, "mm"};  // a pixel on the part: 1 nm to 10 mm
inline const NumberRange kSeed{0.0, 18446744073709551615.0, "", true};

// A number as a person reads it: 0.001, 100000, 1e+308, nan (never 309 digits).
std::string ReadableNumber(double value);

// The check of an option that holds one number (or a list of single numbers: each is checked).
CLI::Validator Within(const NumberRange& range);
// Shorthands: Within({min, max, unit}) and a count Within({min, max, "", true}).
CLI::Validator Within(double min, double max, const std::string& unit = "");
CLI::Validator Count(double min, double max);

// The check of an option whose text holds several numbers, shown as V in `form` ("V,V,V", "VxVxV"): `refusal`
// reads the text and says why it is refused (empty when it is not). Listed with `range`, the span of its numbers.
CLI::Validator NumbersWithin(std::function<std::string(const std::string&)> refusal, const std::string& form,
                             const NumberRange& range, const std::string& description);

// --overlap of tiles: a fraction (0.2) or percent (20 or 20%), from 1 % to 99 % (imaging::ParseOverlap).
CLI::Validator OverlapCheck(const std::string& what);

// Every option of `app` and its subcommands that takes numbers, one line each:
// "COMMAND PATH<TAB>--flag<TAB>FORM<TAB>MIN<TAB>MAX<TAB>whole|real", or "...<TAB>unbounded" for a numeric option
// declared without a span (which then still refuses nan and inf).
std::string NumericOptionList(CLI::App& app);
// Gives every numeric option declared without a span the check that its numbers are finite.
void RefuseNonFinite(CLI::App& app);

}  // namespace fvm::cli
