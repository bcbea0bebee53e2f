#include "imaging/tile_registration.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <utility>
#include <vector>

namespace fvm::imaging {

TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs, double stage_sigma_px) {
  if (!(stage_sigma_px > 0.0)) throw std::invalid_argument("SolveTilePositions: the stage sigma must be positive");
  const int n = static_cast<int>(nominal_px.size());
  const auto at = [](int i) { return static_cast<size_t>(i); };
  // Groups of tiles joined by accepted pairs (union-find); each group's root is its earliest tile.
  std::vector<int> parent(at(n));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    const int ra = find(pair.a), rb = find(pair.b);
    if (ra != rb) parent[at(std::max(ra, rb))] = std::min(ra, rb);
  }
  TilePositions out;
  out.positions_px = nominal_px;
  out.registered.assign(at(n), false);
  out.anchor.resize(at(n));
  out.sigma_px.assign(at(n), Eigen::Vector2d::Zero());
  // Unknowns: x and y of every tile that is not its group's anchor.
  std::vector<int> unknown(at(n), -1);
  int m = 0;
  for (int i = 0; i < n; ++i) {
    out.anchor[at(i)] = find(i);
    if (find(i) != i) unknown[at(i)] = m++;
  }
  for (int i = 0; i < n; ++i) {
    // A tile is registered when its position comes from images: it is linked to its group, or it anchors the
    // first group (whose position is where the measurement's coordinates start, by definition).
    out.registered[at(i)] = unknown[at(i)] >= 0 || i == 0;
  }
  if (m == 0) return out;
  // Normal equations of sum (p_b - p_a - o)' W (p_b - p_a - o) + sum |p - nominal|^2 / stage_sigma^2: a graph
  // Laplacian of 2 x 2 blocks plus the stage's diagonal.
  const double prior = 1.0 / (stage_sigma_px * stage_sigma_px);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * m);
  const auto add_block = [&](int r, int c, const Eigen::Matrix2d& w) {
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) triplets.emplace_back(2 * r + i, 2 * c + j, w(i, j));
    }
  };
  for (int i = 0; i < n; ++i) {
    const int u = unknown[at(i)];
    if (u < 0) continue;
    add_block(u, u, prior * Eigen::Matrix2d::Identity());
    rhs.segment<2>(2 * u) += prior * nominal_px[at(i)];
  }
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    const Eigen::Matrix2d& w = pair.information;
    const int ua = unknown[at(pair.a)], ub = unknown[at(pair.b)];
    const Eigen::Vector2d wo = w * pair.offset_px;
    if (ua >= 0) {
      add_block(ua, ua, w);
      rhs.segment<2>(2 * ua) -= wo;
    } else {
      rhs.segment<2>(2 * ub) += w * nominal_px[at(pair.a)];
    }
    if (ub >= 0) {
      add_block(ub, ub, w);
      rhs.segment<2>(2 * ub) += wo;
    } else {
      rhs.segment<2>(2 * ua) += w * nominal_px[at(pair.b)];
    }
    if (ua >= 0 && ub >= 0) {
      add_block(ua, ub, -w);
      add_block(ub, ua, -w);
    }
  }
  Eigen::SparseMatrix<double> normal(2 * m, 2 * m);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) throw std::runtime_error("tile positions: singular normal equations");
  const Eigen::VectorXd solution = solver.solve(rhs);
  // The variances: the diagonal of the inverse, a column at a time (a few hundred solves of a sparse factor).
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(2 * m);
  for (int i = 0; i < n; ++i) {
    const int u = unknown[at(i)];
    if (u < 0) continue;
    out.positions_px[at(i)] = solution.segment<2>(2 * u);
    for (int k = 0; k < 2; ++k) {
      unit(2 * u + k) = 1.0;
      const double variance = solver.solve(unit)(2 * u + k);
      unit(2 * u + k) = 0.0;
      out.sigma_px[at(i)](k) = std::sqrt(variance);
    }
  }
  return out;
}

void SetImagingThreads(int threads) {
  if (threads < 0) throw std::invalid_argument("SetImagingThreads: give 0 (all cores) or a positive count");
  // OpenCV reads a negative count as "its default", i.e. all cores; 0 would mean no pool at all.
  cv::setNumThreads(threads > 0 ? threads : -1);
}

RegistrationResult RegisterTileGrid(const std::vector<TileImage>& images, const std::vector<GridTile>& tiles,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered) {
  if (images.size() != tiles.size()) throw std::invalid_argument("RegisterTileGrid: one image per tile");
  options.Check();
  std::map<std::pair<int, int>, int> at;
  for (size_t i = 0; i < tiles.size(); ++i) at[{tiles[i].row, tiles[i].col}] = static_cast<int>(i);
  RegistrationResult result;
  std::vector<Eigen::Vector2d> nominal;
  for (size_t i = 0; i < tiles.size(); ++i) {
    nominal.push_back(tiles[i].nominal_px);
    for (const auto& [dr, dc] : {std::pair{0, 1}, std::pair{1, 0}}) {
      const auto it = at.find({tiles[i].row + dr, tiles[i].col + dc});
      if (it == at.end()) continue;
      PairRegistration pair;
      pair.a = static_cast<int>(i);
      pair.b = it->second;
      result.pairs.push_back(pair);
    }
  }
  // Pairs are independent: each writes only its own slot, so the result does not depend on the thread count.
  std::atomic<int> registered{0};
  const int total = static_cast<int>(result.pairs.size());
  const auto register_range = [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      PairRegistration& pair = result.pairs[static_cast<size_t>(k)];
      const size_t a = static_cast<size_t>(pair.a), b = static_cast<size_t>(pair.b);
      pair = RegisterPair(images[a], images[b], tiles[b].nominal_px - tiles[a].nominal_px, options);
      pair.a = static_cast<int>(a);
      pair.b = static_cast<int>(b);
      if (on_pair_registered) on_pair_registered(++registered, total);
    }
  };
  const cv::Range all(0, static_cast<int>(result.pairs.size()));
  if (options.parallel) {
    cv::parallel_for_(all, register_range);
  } else {
    register_range(all);
  }
  result.positions = SolveTilePositions(nominal, result.pairs, options.stage_sigma_px);
  return result;
}

}  // namespace fvm::imaging
