#pragma once
// The steps of a tile grid as its registered pairs show them (after the stage model of NIST MIST [Chalfoun 2017]): a
// real stage steps a little longer or shorter than nominal and drifts sideways by the same amount at every step, and
// repeats each position only to within its repeatability. Estimated from the pairs that register, it predicts the pairs
// that do not, rejects registrations that disagree with it, and is the prior of the global solve.
//
// Pixel frame as in tile_registration.h: x right, y down; offsets are b's top-left corner in a's frame.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "imaging/grid_tile.h"
#include "imaging/tile_pair_registration.h"

namespace fvm::imaging {

struct TileGridSteps {
  // The mean offset of a tile's right neighbour (east: x the step, y the sideways drift per column) and of its
  // lower one (south: y the step, x the drift per row), px: the 2 x 2 map from grid index to pixels.
  Eigen::Vector2d east_px = Eigen::Vector2d::Zero(), south_px = Eigen::Vector2d::Zero();
  // The same from the nominal positions, which the model corrects.
  Eigen::Vector2d nominal_east_px = Eigen::Vector2d::Zero(), nominal_south_px = Eigen::Vector2d::Zero();
  // Which of the four components the pairs determined (east x, east y, south x, south y); the others keep the
  // nominal value. A component needs kMinPairs pairs whose images fix it (not along machining marks).
  std::array<bool, 4> estimated{};
  int east_pairs = 0, south_pairs = 0;  // accepted pairs each direction rests on
  // The stage's repeatability per axis (px, standard deviation of one tile's position about the model): the
  // robust spread of the pairs' offsets about the mean step, over sqrt(2) (a pair differs two positions). 0 when
  // fewer than kMinPairs pairs fix the axis.
  Eigen::Vector2d repeatability_px = Eigen::Vector2d::Zero();
  // What a stage shares along a row or a column (its error is a function of each axis's position, VDI 2617: the x
  // axis's error at a column is the same in every row, the y axis's straightness at a row the same in every column).
  // The spread per axis (px, standard deviation) of the east and south offsets about their median step: the step
  // between two neighbouring columns' (east) or rows' (south) shared positions; 0 where fewer than kMinPairs pairs fix
  // the axis. And each tile's own repeatability about its row's and column's shared positions, per axis: from the
  // differences between two pairs across the same column boundary on neighbouring rows (or the same row boundary on
  // neighbouring columns), which the shared parts cancel from (four tiles' own errors remain: / 2); 0 where fewer
  // than kMinPairs such differences exist.
  Eigen::Vector2d east_spread_px = Eigen::Vector2d::Zero(), south_spread_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d own_px = Eigen::Vector2d::Zero();

  static constexpr int kMinPairs = 3;
  bool Any() const { return estimated[0] || estimated[1] || estimated[2] || estimated[3]; }
  // How far a pair's offset may lie from the model's prediction before it counts as disagreeing, per axis (px):
  // 5 standard deviations of a pair's offset about the mean step and a pixel (a whole-pixel candidate), at least
  // 3 px; `fallback` along an axis the model has no repeatability for. Four rejected a good pair of the 220 of
  // grid6x6, whose 1.5 px stage the MAD of the pairs put at 1.05 px.
  Eigen::Vector2d Tolerance(const Eigen::Vector2d& fallback) const;
  // The correction of tile (row, col)'s nominal position relative to the first tile (row0, col0):
  // (col - col0) (east - nominal east) + (row - row0) (south - nominal south).
  Eigen::Vector2d Correction(int drow, int dcol) const;
};

// The stage's prior of a grid (grid_position_solve.h), per axis (px, standard deviations): each tile sits at its stage
// position plus its column's shared offset, its row's, and its own error.
struct StageAxesPrior {
  Eigen::Vector2d column_step_px = Eigen::Vector2d::Constant(2.0);  // between neighbouring columns' shared offsets
  Eigen::Vector2d row_step_px = Eigen::Vector2d::Constant(2.0);     // between neighbouring rows' shared offsets
  Eigen::Vector2d own_px = Eigen::Vector2d::Constant(2.0);          // a tile about its row's and column's offsets
  // How far the mean steps the positions start from (TileGridSteps' east and south, medians of the pairs) may lie
  // from the grid's: the solve takes a correction of each with this standard deviation per axis, for the pairs to
  // fix. 0: the step held (a component the pairs did not estimate keeps its nominal value, as before). Without it, a
  // tile no pair joins to the others (a hole on every side) was placed as though the median steps were exact: on cut
  // grids of the held-out shape, 2.8 px off with u = 0.8 px.
  Eigen::Vector2d east_mean_px = Eigen::Vector2d::Zero(), south_mean_px = Eigen::Vector2d::Zero();
};

// Whether a pair's information fixes axis k (0 x, 1 y): the directions it determines to better than 0.5 px span the
// axis (to within 18 degrees).
bool PairFixesAxis(const Eigen::Matrix2d& information, int k);

// From the accepted pairs between right (east) and lower (south) neighbours of `tiles`: the median offset per
// direction and axis (robust against a wrong registration), over the pairs whose information fixes that axis to
// better than 0.5 px; the spread from the median absolute deviation.
TileGridSteps EstimateTileGridSteps(const std::vector<GridTile>& tiles, const std::vector<PairRegistration>& pairs);

}  // namespace fvm::imaging
