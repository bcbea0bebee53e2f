#pragma once
// Count, mean, rms, largest and smallest of Euclidean residuals (mm): the statistics every report of fvm quotes,
// for an identification's own residuals as for held-out measurements.

#include <Eigen/Core>
#include <vector>

namespace fvm::stage {

struct ResidualSummary {
  int count = 0;
  double mean_mm = 0, rms_mm = 0, max_mm = 0, min_mm = 0;
};
ResidualSummary Summarize(const std::vector<Eigen::Vector3d>& residuals);

}  // namespace fvm::stage
