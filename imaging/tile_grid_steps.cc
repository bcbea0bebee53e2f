#include "imaging/tile_grid_steps.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/dense_decomposition.h"
#include "core/statistics.h"

namespace fvm::imaging {
namespace {

// Whether a pair's information fixes axis k: the directions it determines to better than 0.5 px span the axis
// (to within 18 degrees). Not the marginal variance: along machining marks the information is rank one and tilted
// by its noise, and the marginal variance across the marks is then as large as along them.
bool Fixes(const Eigen::Matrix2d& information, int k) {
  const auto directions = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(information, "a tile pair's information");
  double spanned = 0.0;
  for (int j = 0; j < 2; ++j) {
    if (directions.eigenvalues()(j) > 4.0) spanned += std::pow(directions.eigenvectors()(k, j), 2);
  }
  return spanned > 0.95 * 0.95;
}

}  // namespace

Eigen::Vector2d TileGridSteps::Tolerance(const Eigen::Vector2d& fallback) const {
  Eigen::Vector2d out;
  for (int k = 0; k < 2; ++k) {
    out(k) = repeatability_px(k) > 0.0 ? std::max(5.0 * std::sqrt(2.0) * repeatability_px(k) + 1.0, 3.0) : fallback(k);
  }
  return out;
}

Eigen::Vector2d TileGridSteps::Correction(int drow, int dcol) const {
  return dcol * (east_px - nominal_east_px) + drow * (south_px - nominal_south_px);
}

TileGridSteps EstimateTileGridSteps(const std::vector<GridTile>& tiles, const std::vector<PairRegistration>& pairs) {
  TileGridSteps model;
  // Per direction (0 east, 1 south): nominal offsets, and per axis the measured ones that the pair fixes.
  std::array<std::vector<double>, 2> nominal_x, nominal_y;
  std::array<std::array<std::vector<double>, 2>, 2> measured;
  for (const auto& pair : pairs) {
    const GridTile& a = tiles[static_cast<size_t>(pair.a)];
    const GridTile& b = tiles[static_cast<size_t>(pair.b)];
    int direction = -1;
    if (b.row == a.row && b.col == a.col + 1) direction = 0;
    if (b.col == a.col && b.row == a.row + 1) direction = 1;
    if (direction < 0) continue;
    const Eigen::Vector2d nominal = b.nominal_px - a.nominal_px;
    nominal_x[static_cast<size_t>(direction)].push_back(nominal.x());
    nominal_y[static_cast<size_t>(direction)].push_back(nominal.y());
    if (!pair.accepted) continue;
    (direction == 0 ? model.east_pairs : model.south_pairs) += 1;
    for (int k = 0; k < 2; ++k) {
      if (Fixes(pair.information, k)) measured[static_cast<size_t>(direction)][static_cast<size_t>(k)].push_back(pair.offset_px(k));
    }
  }
  std::array<Eigen::Vector2d*, 2> step = {&model.east_px, &model.south_px};
  std::array<Eigen::Vector2d*, 2> nominal_step = {&model.nominal_east_px, &model.nominal_south_px};
  std::array<std::vector<double>, 2> deviations;  // per axis, |offset - median| over both directions
  for (size_t d = 0; d < 2; ++d) {
    if (nominal_x[d].empty()) continue;
    *nominal_step[d] = Eigen::Vector2d(Median(nominal_x[d]), Median(nominal_y[d]));
    *step[d] = *nominal_step[d];
    for (size_t k = 0; k < 2; ++k) {
      const std::vector<double>& values = measured[d][k];
      if (values.size() < static_cast<size_t>(TileGridSteps::kMinPairs)) continue;
      const double median = Median(values);
      (*step[d])(static_cast<Eigen::Index>(k)) = median;
      model.estimated[2 * d + k] = true;
      for (const double v : values) deviations[k].push_back(std::abs(v - median));
    }
  }
  for (size_t k = 0; k < 2; ++k) {
    if (deviations[k].size() < static_cast<size_t>(TileGridSteps::kMinPairs)) continue;
    // 1.4826 MAD: the standard deviation of a normal distribution; a pair differs two positions: / sqrt(2). A
    // floor of 0.05 px: a stage that repeats better than registration measures is still no perfect one.
    model.repeatability_px(static_cast<Eigen::Index>(k)) =
        std::max(1.4826 * Median(deviations[k]) / std::sqrt(2.0), 0.05);
  }
  return model;
}

}  // namespace fvm::imaging
