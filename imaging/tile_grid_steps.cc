#include "imaging/tile_grid_steps.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "core/dense_decomposition.h"
#include "core/statistics.h"

namespace fvm::imaging {

// Not the marginal variance: along machining marks the information is rank one and tilted by its noise, and the
// marginal variance across the marks is then as large as along them.
bool PairFixesAxis(const Eigen::Matrix2d& information, int k) {
  const auto directions = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(information, "a tile pair's information");
  double spanned = 0.0;
  for (int j = 0; j < 2; ++j) {
    if (directions.eigenvalues()(j) > 4.0) spanned += std::pow(directions.eigenvectors()(k, j), 2);
  }
  return spanned > 0.95 * 0.95;
}

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
  // Per direction and axis, the offsets that fix it by (boundary, across): an east pair of row r between columns c
  // and c + 1 is (c, r), a south pair of column c between rows r and r + 1 is (r, c).
  std::array<std::array<std::map<std::pair<int, int>, double>, 2>, 2> by_place;
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
      if (!PairFixesAxis(pair.information, k)) continue;
      measured[static_cast<size_t>(direction)][static_cast<size_t>(k)].push_back(pair.offset_px(k));
      const std::pair<int, int> place = direction == 0 ? std::pair{a.col, a.row} : std::pair{a.row, a.col};
      by_place[static_cast<size_t>(direction)][static_cast<size_t>(k)][place] = pair.offset_px(k);
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
      double square = 0.0;
      for (const double v : values) {
        deviations[k].push_back(std::abs(v - median));
        square += (v - median) * (v - median) / static_cast<double>(values.size());
      }
      // The rms, not a robust spread: the shared steps of a few columns are a few distinct values, each repeated
      // row by row, and a median of their deviations can land on the nearest one.
      (d == 0 ? model.east_spread_px : model.south_spread_px)(static_cast<Eigen::Index>(k)) = std::sqrt(square);
    }
  }
  std::array<std::vector<double>, 2> own;  // per axis, |difference| of two pairs across one boundary, side by side
  for (size_t d = 0; d < 2; ++d) {
    for (size_t k = 0; k < 2; ++k) {
      for (const auto& [place, offset] : by_place[d][k]) {
        const auto next = by_place[d][k].find({place.first, place.second + 1});
        if (next != by_place[d][k].end()) own[k].push_back(std::abs(next->second - offset));
      }
    }
  }
  for (size_t k = 0; k < 2; ++k) {
    if (own[k].size() < static_cast<size_t>(TileGridSteps::kMinPairs)) continue;
    // A difference holds four tiles' own errors: its standard deviation over 2 (1.4826 MAD: robust against a pair
    // the loops left wrong); the floor of the repeatability below.
    model.own_px(static_cast<Eigen::Index>(k)) = std::max(1.4826 * Median(own[k]) / 2.0, 0.05);
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
