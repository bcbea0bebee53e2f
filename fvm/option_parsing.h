#pragma once
// Option values that are lists of numbers (--tool 0,0,100, --pose X,Y,Z,A,B,C, --machine 2500x1500x1200): parsed
// one way for every command, locale-independent and whole-field ("1.5mm" is refused), with an example in each
// message. Parse errors are InputError; as CLI11 validators (Parses) they become usage errors (exit 2).

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "artefacts/simulation/machine_tool_simulation.h"
#include "stage/pose.h"

namespace fvm::cli {

// Exactly `count` finite numbers separated by commas.
std::vector<double> ParseNumbers(std::string_view text, size_t count, const std::string& what, const std::string& example);
// A comma-separated list of any length, e.g. the encoder heights "-50,-40" of calibration scans.
std::vector<double> ParseNumberList(const std::string& text, const std::string& what, const std::string& example);
Eigen::Vector3d ParseVector3(std::string_view text, const std::string& what, const std::string& example);
// X,Y,Z (mm), A,B,C (XYZ Euler angles, deg): a tracker's pose in the machine frame.
stage::Pose ParsePose(std::string_view text, const std::string& what);
// "LXxLYxLZ" or "LXxLYxLZ@X0,Y0,Z0" (mm): the travels of a machine's three axes.
artefacts::Workspace ParseMachine(std::string_view text);

// A CLI11 check that runs one of the parsers above: its message becomes a usage error (exit 2).
template <typename Parse>
CLI::Validator Parses(Parse parse, const std::string& name) {
  return CLI::Validator(
      [parse](std::string& text) -> std::string {
        try {
          parse(text);
        } catch (const std::exception& e) {
          return e.what();
        }
        return {};
      },
      "", name);
}

}  // namespace fvm::cli
