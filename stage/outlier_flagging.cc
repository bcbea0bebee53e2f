#include "stage/outlier_flagging.h"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/statistics.h"

namespace fvm::stage {
namespace {

// What sets observation i's residual apart from those of its neighbours in the same group (the calottes before and
// after it along the bar): r_i less their mean or, at the end of a bar, less the straight line through the two
// before it. Smooth along the bar, a missing effect leaves little of it; a blunder leaves nearly all. `noise` is
// its variance in units of one residual's (white noise): 1 + 1/2, or 1 + 4 + 1 for the straight line.
struct Spike {
  Eigen::Vector3d value;
  double noise;
};

Spike SpikeOf(const std::vector<Observation>& observations, const std::vector<Eigen::Vector3d>& residuals, size_t i) {
  const auto same = [&](long k) {
    return k >= 0 && k < static_cast<long>(observations.size()) && observations[static_cast<size_t>(k)].group == observations[i].group;
  };
  const long n = static_cast<long>(i);
  const auto r = [&](long k) { return residuals[static_cast<size_t>(k)]; };
  if (same(n - 1) && same(n + 1)) return {residuals[i] - (r(n - 1) + r(n + 1)) / 2, 1.5};
  if (same(n - 2) && same(n - 1)) return {residuals[i] - (2 * r(n - 1) - r(n - 2)), 6.0};
  if (same(n + 2) && same(n + 1)) return {residuals[i] - (2 * r(n + 1) - r(n + 2)), 6.0};
  if (same(n - 1)) return {residuals[i] - r(n - 1), 2.0};
  if (same(n + 1)) return {residuals[i] - r(n + 1), 2.0};
  return {residuals[i], 1.0};
}

}  // namespace

double RobustSigma(const std::vector<Eigen::Vector3d>& residuals, double floor_mm) {
  std::vector<double> components;
  for (const Eigen::Vector3d& r : residuals) components.insert(components.end(), {std::abs(r.x()), std::abs(r.y()), std::abs(r.z())});
  if (components.empty()) return floor_mm;
  return std::max(1.4826 * HighMedian(std::move(components)), floor_mm);
}

std::vector<int> FlagOutliers(const ParameterLayout& layout, const MeasurementSet& identify, Anchor anchor,
                              const std::vector<Eigen::Vector3d>& fit_residuals, const IdentificationOptions& base_options,
                              double alpha) {
  std::vector<int> flagged;
  std::vector<int> index(identify.observations.size());
  std::iota(index.begin(), index.end(), 0);
  std::vector<Observation> kept = identify.observations;
  std::vector<Eigen::Vector3d> residuals = fit_residuals;
  const boost::math::chi_squared_distribution<double> chi2(3.0);
  const double limit = boost::math::quantile(boost::math::complement(chi2, alpha / static_cast<double>(kept.size())));
  const size_t most = kept.size() / 5;  // beyond a fifth of the centres, the "outliers" are the model's failure
  while (flagged.size() < most && !residuals.empty()) {
    const double sigma = RobustSigma(residuals, base_options.noise_floor_mm);
    // The worst centre beyond the limit that also stands out from its neighbours by as much (SpikeOf): a failed
    // sphere fit moves one centre, while an effect the model lacks moves its neighbours along the bar with it.
    std::vector<size_t> order(residuals.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return residuals[a].squaredNorm() > residuals[b].squaredNorm(); });
    size_t worst = residuals.size();
    for (const size_t i : order) {
      if (residuals[i].squaredNorm() / (sigma * sigma) <= limit) break;
      const Spike spike = SpikeOf(kept, residuals, i);
      if (spike.value.squaredNorm() / (spike.noise * sigma * sigma) > limit) {
        worst = i;
        break;
      }
    }
    if (worst == residuals.size()) break;
    flagged.push_back(index[worst]);
    kept.erase(kept.begin() + static_cast<long>(worst));
    index.erase(index.begin() + static_cast<long>(worst));
    IdentificationOptions o = base_options;
    o.anchor = anchor;
    o.anchors = identify.anchors;
    try {
      residuals = Identify(layout, kept, o).residuals;
    } catch (const std::invalid_argument&) {
      break;  // too few centres left for the model: stop flagging
    }
  }
  return flagged;
}

}  // namespace fvm::stage
