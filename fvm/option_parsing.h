#pragma once
// Option values that are lists of numbers (--tool 0,0,100, --pose X,Y,Z,A,B,C, --machine 2500x1500x1200): parsed
// one way for every command, locale-independent and whole-field ("1.5mm" is refused), every number finite and
// within its span (fvm/option_ranges.h), with an example in each message. Parse errors are InputError; as CLI11
// checks (the *Check functions, Parses) they become usage errors (exit 2).

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "artefacts/machine_truth.h"
#include "fvm/option_ranges.h"
#include "stage/pose.h"

namespace fvm::cli {

// Exactly `count` numbers separated by `separator` (count 0: one or more), each within `range`.
std::vector<double> ParseNumbers(std::string_view text, size_t count, const std::string& what, const std::string& example,
                                 const NumberRange& range = kCoordinateMm, char separator = ',');
// A comma-separated list of any length, e.g. the encoder heights "-50,-40" of calibration scans.
std::vector<double> ParseNumberList(const std::string& text, const std::string& what, const std::string& example);
Eigen::Vector3d ParseVector3(std::string_view text, const std::string& what, const std::string& example,
                             const NumberRange& range = kCoordinateMm);
// X,Y,Z (mm), A,B,C (XYZ Euler angles, deg): a tracker's pose in the machine frame.
stage::Pose ParsePose(std::string_view text, const std::string& what);
// "LXxLYxLZ" or "LXxLYxLZ@X0,Y0,Z0" (mm): the travels of a machine's three axes.
artefacts::Workspace ParseMachine(std::string_view text);

// CLI11 checks of the forms above, listed by fvm --list-numeric-options with the span of their numbers.
CLI::Validator NumbersCheck(size_t count, const std::string& what, const std::string& example,
                            const NumberRange& range = kCoordinateMm, char separator = ',');
CLI::Validator PoseCheck(const std::string& what);
CLI::Validator MachineCheck();

// The message of what `parse` throws on `text`, or empty when it parses.
template <typename Parse>
std::string RefusalOf(const Parse& parse, const std::string& text) {
  try {
    parse(text);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

// A CLI11 check that runs one of the parsers above: its message becomes a usage error (exit 2).
template <typename Parse>
CLI::Validator Parses(Parse parse, const std::string& name) {
  return CLI::Validator([parse](std::string& text) { return RefusalOf(parse, text); }, "", name);
}
// The same for a parser of numbers (their span `range`, shown as V in `form`), listed by --list-numeric-options.
template <typename Parse>
CLI::Validator ParsesWithin(Parse parse, const std::string& form, const NumberRange& range, const std::string& description) {
  return NumbersWithin([parse](const std::string& text) { return RefusalOf(parse, text); }, form, range, description);
}

}  // namespace fvm::cli
