#include "workflows/overlap_block_scatter.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace fvm::workflows {

imaging::CorrespondenceOptions BandMatching(imaging::CorrespondenceOptions matching, double band_px) {
  if (band_px >= 4.0 * matching.window_px) return matching;
  int window = static_cast<int>(std::floor(band_px / 4.0));
  if (window % 2 == 0) --window;
  matching.window_px = std::max(7, window);
  matching.pyramid_levels = std::min(matching.pyramid_levels, 1);
  matching.grid_step_px = std::max(2, std::min(matching.grid_step_px, static_cast<int>(std::floor(band_px / 10.0))));
  return matching;
}

double OverlapBlockScatter(const std::vector<imaging::PairCorrespondences>& matched,
                           const imaging::FieldDistortionFit& fit, int min_points, int* dof) {
  constexpr int kBlocks = 4;
  const double sigma = fit.point_sigma_px;
  double chi2 = 0.0;
  int blocks_dof = 0;
  for (const imaging::PairCorrespondences& p : matched) {
    if (static_cast<int>(p.a_px.size()) < min_points) continue;
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    for (size_t m = 0; m < p.a_px.size(); ++m) step += p.a_px[m] - p.b_px[m];
    const bool along_x = std::abs(step.x()) >= std::abs(step.y());
    std::vector<std::pair<double, Eigen::Vector2d>> residuals;  // (place along the band, residual)
    for (size_t m = 0; m < p.a_px.size(); ++m) {
      const Eigen::Vector2d r = fit.positions_px[static_cast<size_t>(p.a)] - fit.positions_px[static_cast<size_t>(p.b)] +
                                p.a_px[m] - p.b_px[m] + fit.field.Displacement(p.a_px[m]) - fit.field.Displacement(p.b_px[m]);
      if (r.cwiseAbs().maxCoeff() <= 3.0 * sigma) residuals.emplace_back(along_x ? p.a_px[m].y() : p.a_px[m].x(), r);
    }
    const int n = static_cast<int>(residuals.size());
    if (n < 2 * kBlocks) continue;
    std::sort(residuals.begin(), residuals.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& entry : residuals) mean += entry.second;
    mean /= n;
    for (int b = 0; b < kBlocks; ++b) {
      const int first = b * n / kBlocks, end = (b + 1) * n / kBlocks;
      Eigen::Vector2d block = Eigen::Vector2d::Zero();
      for (int m = first; m < end; ++m) block += residuals[static_cast<size_t>(m)].second;
      block /= end - first;
      chi2 += (block - mean).squaredNorm() * (end - first) / (sigma * sigma);
    }
    blocks_dof += 2 * (kBlocks - 1);
  }
  if (dof) *dof = blocks_dof;
  return blocks_dof > 0 && sigma > 0.0 ? std::max(1.0, std::sqrt(chi2 / blocks_dof)) : 1.0;
}

}  // namespace fvm::workflows
