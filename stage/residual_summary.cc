#include "stage/residual_summary.h"

#include <algorithm>
#include <cmath>

namespace fvm::stage {

ResidualSummary Summarize(const std::vector<Eigen::Vector3d>& residuals) {
  ResidualSummary s;
  s.count = static_cast<int>(residuals.size());
  double sum = 0, sum_sq = 0;
  s.min_mm = residuals.empty() ? 0.0 : residuals.front().norm();
  for (const Eigen::Vector3d& r : residuals) {
    sum += r.norm();
    sum_sq += r.squaredNorm();
    s.max_mm = std::max(s.max_mm, r.norm());
    s.min_mm = std::min(s.min_mm, r.norm());
  }
  if (s.count > 0) {
    s.mean_mm = sum / s.count;
    s.rms_mm = std::sqrt(sum_sq / s.count);
  }
  return s;
}

}  // namespace fvm::stage
