#pragma once
// The report of `fvm verify --report DIR`: an HTML page with tables (summary, tracker pose, squareness, fixed
// terms with their reasons) and three SVG plots: the 21 error functions with their 95 % bands, one row of panels
// per axis; the volumetric error of every point before and after, sorted; and a map of it over the workspace.
// Units are the report's: um for translations and errors, urad for rotations, mm for machine positions.

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fvm::report {

struct MachineReportData {
  std::string title;
  std::vector<std::pair<std::string, std::string>> summary;

  // One error function sampled over its axis' travel, relative to its value at the axis' origin.
  struct Curve {
    std::string name;                // "xTx"
    std::vector<double> value;       // um or urad, one per position
    std::vector<double> u;           // standard uncertainty of each value; the plot shows +-2u (k = 2)
  };
  struct AxisFunctions {
    std::string axis;                  // "X"
    std::vector<double> position_mm;   // the axis coordinate of each sample
    std::vector<Curve> translations;   // um: kTx, kTy, kTz
    std::vector<Curve> rotations;      // urad: kRx, kRy, kRz
  };
  std::array<AxisFunctions, 3> functions;

  // The volumetric error (|model - reading|) of one point, before (ideal machine) and after (identified model).
  struct PointError {
    double x_mm, y_mm, z_mm, before_um, after_um;
  };
  std::vector<PointError> readings;    // the fitted points
  std::vector<PointError> validation;  // held-out points, may be empty

  struct Table {
    std::string heading, note;  // note: a sentence under the heading, may be empty
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
  };
  std::vector<Table> tables;  // after the summary, before the plots
};

// Writes DIR/index.html, error_functions.svg, volumetric_errors.svg and error_map.svg, each atomically, the page
// last. Throws fvm::InputError naming DIR when it cannot be written, leaving nothing it created behind. Not
// thread-safe (PLplot).
void WriteMachineReport(const std::filesystem::path& dir, const MachineReportData& data);

}  // namespace fvm::report
