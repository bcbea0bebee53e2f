#pragma once
// Count, mean, rms, largest and smallest of Euclidean residuals (mm): the statistics every report of fvm quotes,
// for an identification's own residuals as for held-out measurements, a machine's volumetric errors and a
// simulation's truth. The um figures are the same numbers as machine-tool studies quote them.

#include <Eigen/Core>
#include <vector>

namespace fvm::stage {

struct ResidualSummary {
  int count = 0;
  double mean_mm = 0, rms_mm = 0, max_mm = 0, min_mm = 0;

  double mean_um() const { return mean_mm * 1e3; }
  double rms_um() const { return rms_mm * 1e3; }
  double max_um() const { return max_mm * 1e3; }
  double min_um() const { return min_mm * 1e3; }
};
ResidualSummary Summarize(const std::vector<Eigen::Vector3d>& residuals);

}  // namespace fvm::stage
