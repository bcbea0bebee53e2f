#include "imaging/grid_position_solve.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace fvm::imaging {
namespace {

// Normal equations of a sum of terms (sum_j s_j x_j - d)' W (sum_j s_j x_j - d) over 2-vector unknowns x_j; a
// known value has index -1 and is already moved into d.
struct GridNormalEquations {
  explicit GridNormalEquations(int blocks) : rhs(Eigen::VectorXd::Zero(2 * blocks)), size(2 * blocks) {}
  void Add(const std::vector<std::pair<int, double>>& terms, const Eigen::Matrix2d& w, const Eigen::Vector2d& d) {
    for (const auto& [j, sj] : terms) {
      if (j < 0) continue;
      rhs.segment<2>(2 * j) += sj * (w * d);
      for (const auto& [l, sl] : terms) {
        if (l < 0) continue;
        for (int r = 0; r < 2; ++r) {
          for (int c = 0; c < 2; ++c) triplets.emplace_back(2 * j + r, 2 * l + c, sj * sl * w(r, c));
        }
      }
    }
  }
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs;
  int size;
};

// The floor of every spread: no stage repeats better than registration measures (TileGridSteps' floor).
constexpr double kFloorPx = 0.05;

Eigen::Matrix2d Weight(const Eigen::Vector2d& sigma_px) { return sigma_px.cwiseAbs2().cwiseInverse().asDiagonal(); }

struct GridSolution {
  std::vector<Eigen::Vector2d> positions_px;
  std::vector<Eigen::Vector2d> sigma_px;  // of p_i - p_0, per axis
};

// The solve over the accepted pairs and the stage; each tile's standard uncertainty against the first tile, whose
// position is exact.
GridSolution SolveGrid(const std::vector<GridTile>& tiles, const std::vector<Eigen::Vector2d>& stage_px,
                       const std::vector<PairRegistration>& pairs, const StageAxesPrior& prior) {
  const int n = static_cast<int>(tiles.size());
  const auto at = [](int i) { return static_cast<size_t>(i); };
  int row0 = tiles[0].row, row1 = tiles[0].row, col0 = tiles[0].col, col1 = tiles[0].col;
  for (const auto& t : tiles) row0 = std::min(row0, t.row), row1 = std::max(row1, t.row), col0 = std::min(col0, t.col), col1 = std::max(col1, t.col);
  // Unknowns: tiles 1 .. n - 1, then every column's offset, then every row's but the first tile's (the gauge: the
  // first tile's row offset is nil, its column's then follows from its own term).
  const auto tile = [&](int i) { return i == 0 ? -1 : i - 1; };
  const auto column = [&](int c) { return n - 1 + (c - col0); };
  const auto row = [&](int r) {
    if (r == tiles[0].row) return -1;
    return n - 1 + (col1 - col0 + 1) + (r - row0) - (r > tiles[0].row ? 1 : 0);
  };
  // Then the corrections of the mean steps east and south (StageAxesPrior::east_mean_px), which act on a tile by its
  // columns and rows from the first.
  const int east = n - 1 + (col1 - col0 + 1) + (row1 - row0), south = east + 1;
  const int blocks = south + 1;
  GridNormalEquations equations(blocks);
  const Eigen::Matrix2d own = Weight(prior.own_px);
  for (int i = 0; i < n; ++i) {
    // p_i - a_col - b_row - dcol e - drow s = stage_i (the first tile: - a_col - b_row = 0).
    const Eigen::Vector2d d = i == 0 ? Eigen::Vector2d::Zero() : stage_px[at(i)];
    const double dcol = tiles[at(i)].col - tiles[0].col, drow = tiles[at(i)].row - tiles[0].row;
    equations.Add({{tile(i), 1.0}, {column(tiles[at(i)].col), -1.0}, {row(tiles[at(i)].row), -1.0}, {east, -dcol},
                   {south, -drow}},
                  own, d);
  }
  // A held step (0) as a correction of a thousandth of a pixel: the same positions as without the unknown.
  equations.Add({{east, 1.0}}, Weight(prior.east_mean_px.cwiseMax(1e-3)), Eigen::Vector2d::Zero());
  equations.Add({{south, 1.0}}, Weight(prior.south_mean_px.cwiseMax(1e-3)), Eigen::Vector2d::Zero());
  for (int c = col0; c < col1; ++c) {
    equations.Add({{column(c + 1), 1.0}, {column(c), -1.0}}, Weight(prior.column_step_px), Eigen::Vector2d::Zero());
  }
  for (int r = row0; r < row1; ++r) {
    equations.Add({{row(r + 1), 1.0}, {row(r), -1.0}}, Weight(prior.row_step_px), Eigen::Vector2d::Zero());
  }
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    // p_b - p_a = offset; the first tile's position is known.
    Eigen::Vector2d d = pair.offset_px;
    if (pair.a == 0) d += stage_px[0];
    if (pair.b == 0) d -= stage_px[0];
    equations.Add({{tile(pair.b), 1.0}, {tile(pair.a), -1.0}}, pair.information, d);
  }
  Eigen::SparseMatrix<double> normal(equations.size, equations.size);
  normal.setFromTriplets(equations.triplets.begin(), equations.triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) throw std::runtime_error("tile positions: singular normal equations");
  const Eigen::VectorXd solution = solver.solve(equations.rhs);
  GridSolution out;
  out.positions_px.assign(at(n), stage_px[0]);
  out.sigma_px.assign(at(n), Eigen::Vector2d::Zero());
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(equations.size);
  for (int i = 1; i < n; ++i) out.positions_px[at(i)] = solution.segment<2>(2 * tile(i));
  for (int i = 1; i < n; ++i) {
    for (int k = 0; k < 2; ++k) {
      // The variance of tile i's coordinate k against the first tile's exact position: e' N^-1 e, e its unit vector.
      unit(2 * tile(i) + k) = 1.0;
      out.sigma_px[at(i)](k) = std::sqrt(std::max(unit.dot(solver.solve(unit)), 0.0));
      unit(2 * tile(i) + k) = 0.0;
    }
  }
  return out;
}

}  // namespace

StageAxesPrior StageAxesPriorOf(const TileGridSteps& steps, double fallback_px, double declared_px) {
  StageAxesPrior prior;
  for (int k = 0; k < 2; ++k) {
    if (!(steps.repeatability_px(k) > 0.0)) {
      // No pair fixes the axis (machining marks along it): the stage as declared, each tile on its own.
      prior.own_px(k) = declared_px;
      prior.column_step_px(k) = prior.row_step_px(k) = kFloorPx;
      continue;
    }
    prior.own_px(k) = steps.own_px(k) > 0.0 ? steps.own_px(k) : steps.repeatability_px(k);
    // A pair's offset differs its two tiles' shared offsets and their own errors: the step is what is left.
    const double own2 = 2.0 * prior.own_px(k) * prior.own_px(k);
    const auto step = [&](double spread) {
      return spread > 0.0 ? std::sqrt(std::max(spread * spread - own2, kFloorPx * kFloorPx)) : fallback_px;
    };
    prior.column_step_px(k) = step(steps.east_spread_px(k));
    prior.row_step_px(k) = step(steps.south_spread_px(k));
    // The mean steps as loosely as the plausible range: the pairs fix them where they estimated them.
    prior.east_mean_px(k) = steps.estimated[static_cast<size_t>(k)] ? fallback_px : 0.0;
    prior.south_mean_px(k) = steps.estimated[static_cast<size_t>(2 + k)] ? fallback_px : 0.0;
  }
  return prior;
}

TilePositions SolveGridPositions(const std::vector<GridTile>& tiles, const std::vector<Eigen::Vector2d>& stage_px,
                                 const std::vector<PairRegistration>& pairs, const StageAxesPrior& prior,
                                 double registered_within_px) {
  if (tiles.size() != stage_px.size() || tiles.empty()) {
    throw std::invalid_argument("SolveGridPositions: one stage position per tile, and at least one tile");
  }
  if (!(prior.own_px.minCoeff() > 0.0 && prior.column_step_px.minCoeff() > 0.0 && prior.row_step_px.minCoeff() > 0.0)) {
    throw std::invalid_argument("SolveGridPositions: the stage's spreads must be positive");
  }
  TilePositions out;
  out.anchor = PairGroups(static_cast<int>(tiles.size()), pairs);
  // The mean steps corrected only where the pairs leave groups apart (a hole on every side of a tile, pairs that
  // failed): there they are the only link, and their uncertainty is the groups'. Where the pairs join every tile,
  // the pairs' median steps stand (robust against a pair that misregistered; corrected, weak pairs pulled them: the
  // real strip's overlap correlation 0.786 -> 0.785).
  StageAxesPrior used = prior;
  if (std::all_of(out.anchor.begin(), out.anchor.end(), [](int a) { return a == 0; })) {
    used.east_mean_px.setZero(), used.south_mean_px.setZero();
  }
  const GridSolution solved = SolveGrid(tiles, stage_px, pairs, used);
  // No accepted pair: every tile where the stage put it, exactly (the solve's would be that to round-off).
  const bool any = std::any_of(pairs.begin(), pairs.end(), [](const PairRegistration& p) { return p.accepted; });
  out.positions_px = any ? solved.positions_px : stage_px;
  out.sigma_px = solved.sigma_px;
  // Registered: the earliest tile of the first group, and a tile that the images place against its group's earliest
  // along both axes to within `registered_within_px`. The images alone: each tile free to 1000 px on its own, not
  // through rows and columns (whose shared offsets pin a block of tiles to others), so that a direction no pair fixes
  // spreads that far.
  const TilePositions images = SolveTilePositions(stage_px, pairs, 1e3, Eigen::Vector2d::Zero());
  out.registered.assign(tiles.size(), false);
  out.registered[0] = true;
  for (size_t i = 1; i < tiles.size(); ++i) {
    out.registered[i] = out.anchor[i] != static_cast<int>(i) && images.sigma_px[i].maxCoeff() < registered_within_px;
  }
  return out;
}

}  // namespace fvm::imaging
