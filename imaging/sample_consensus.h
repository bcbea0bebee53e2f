#pragma once
// The seeded random-sample search for a shape among stray points, shared by the sphere fit (imaging/sphere_fit.cc)
// and the shape fit (imaging/shape_fit.cc): shapes through minimal samples (a sphere through 4 points, a plane
// through 3), each scored on at most 2000 of the points, either by the median of the squared residuals (least
// median of squares, [Rousseeuw 1984]) or by MSAC's truncated sum of squares ([Torr 2000]). The score only ranks
// the hypotheses; the caller takes the consensus set over all points.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "core/statistics.h"

namespace fvm::imaging {

template <typename Shape>
struct ConsensusSearch {
  std::optional<Shape> best;  // none: every sample was degenerate
  double score = std::numeric_limits<double>::infinity();  // least median: the median squared residual (mm^2)
  std::size_t scored_points = 0;
};

// `make(sample)` gives the shape through a sample of kSample points, or nullopt for a degenerate or implausible
// one; `residual(shape, point)` the point's signed distance from it (mm). Scored by the median of squares, or
// with `msac_threshold_mm` by MSAC with that threshold. The same seed draws the same samples.
template <std::size_t kSample, typename Shape, typename Make, typename Residual>
ConsensusSearch<Shape> SearchConsensus(std::span<const Eigen::Vector3d> points, std::uint64_t seed, int iterations,
                                       std::optional<double> msac_threshold_mm, const Make& make,
                                       const Residual& residual) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::vector<std::size_t> subset;
  const std::size_t score_points = std::min<std::size_t>(points.size(), 2000);
  for (std::size_t i = 0; i < score_points; ++i) subset.push_back(points.size() <= 2000 ? i : pick(rng));
  const double t2 = msac_threshold_mm ? *msac_threshold_mm * *msac_threshold_mm : 0.0;
  ConsensusSearch<Shape> search;
  search.scored_points = subset.size();
  std::vector<double> squared;  // least median: the subset's squared residuals
  for (int it = 0; it < iterations; ++it) {
    std::array<Eigen::Vector3d, kSample> sample;
    for (Eigen::Vector3d& p : sample) p = points[pick(rng)];
    const std::optional<Shape> shape = make(sample);
    if (!shape) continue;
    double score = 0;
    if (msac_threshold_mm) {
      for (const std::size_t i : subset) {
        const double r = residual(*shape, points[i]);
        score += std::min(r * r, t2);
      }
    } else {
      squared.clear();
      for (const std::size_t i : subset) squared.push_back(std::pow(residual(*shape, points[i]), 2));
      score = HighMedianInPlace(squared);
    }
    if (score < search.score) search.score = score, search.best = shape;
  }
  return search;
}

// The consensus threshold of a least-median search: 2.5 robust standard deviations of the best shape's residuals,
// with Rousseeuw and Leroy's small-sample factor (1 + 5 / (n - p)) for `parameters` p, never below `floor_mm`.
inline double LeastMedianThreshold(double median_squared_mm2, std::size_t scored_points, int parameters,
                                   double floor_mm) {
  const double n = static_cast<double>(scored_points);
  const double sigma = 1.4826 * (1.0 + 5.0 / std::max(1.0, n - parameters)) * std::sqrt(median_squared_mm2);
  return std::max(2.5 * sigma, floor_mm);
}

}  // namespace fvm::imaging
