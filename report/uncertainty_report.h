#pragma once
// The report of `fvm uncertainty --report DIR`: a summary, the distribution of the final and validation mean errors
// over the Monte Carlo runs (histograms), each point's 95 % ellipsoid seen from above (its shadow on the XY plane),
// and the numbers as CSV.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fvm::report {

struct UncertaintyReportData {
  std::string title;
  std::vector<std::pair<std::string, std::string>> summary;
  std::vector<double> final_mean_um;       // one per run
  std::vector<double> validation_mean_um;  // one per run, empty without validation
  struct Point {
    std::string id;
    double x_mm, y_mm, z_mm, u95_um;
    double semi_axis_um[3];  // of the 95 % ellipsoid, ascending
    double covariance_xy_um2[3] = {0, 0, 0};  // xx, xy, yy of the covariance: the ellipsoid's shadow in the XY view
  };
  std::vector<Point> points;
};

// index.html, distribution.svg, u95_map.svg, points.csv, runs.csv. Throws fvm::InputError when DIR cannot be written.
void WriteUncertaintyReport(const std::filesystem::path& dir, const UncertaintyReportData& data);

}  // namespace fvm::report
