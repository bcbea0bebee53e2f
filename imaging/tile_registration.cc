#include "imaging/tile_registration.h"

#include <Eigen/LU>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <functional>
#include <string>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/statistics.h"
#include "imaging/grid_position_solve.h"
#include "imaging/overlap_correlation.h"
#include "imaging/registration_information.h"

namespace fvm::imaging {

std::vector<int> PairGroups(int n, const std::vector<PairRegistration>& pairs) {
  const auto at = [](int i) { return static_cast<size_t>(i); };
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
  std::vector<int> group(at(n));
  for (int i = 0; i < n; ++i) group[at(i)] = find(i);
  return group;
}

TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs, double stage_sigma_px,
                                 const Eigen::Vector2d& unregistered_sigma_px) {
  if (!(stage_sigma_px > 0.0)) throw std::invalid_argument("SolveTilePositions: the stage sigma must be positive");
  const int n = static_cast<int>(nominal_px.size());
  const auto at = [](int i) { return static_cast<size_t>(i); };
  TilePositions out;
  out.positions_px = nominal_px;
  out.registered.assign(at(n), false);
  out.anchor = PairGroups(n, pairs);  // each group's root is its earliest tile
  out.sigma_px.assign(at(n), Eigen::Vector2d::Zero());
  // Unknowns: x and y of every tile that is not its group's anchor.
  std::vector<int> unknown(at(n), -1);
  int m = 0;
  for (int i = 0; i < n; ++i) {
    if (out.anchor[at(i)] != i) unknown[at(i)] = m++;
  }
  for (int i = 0; i < n; ++i) {
    // A tile is registered when its position comes from images: it is linked to its group, or it anchors the
    // first group (whose position is where the measurement's coordinates start, by definition).
    out.registered[at(i)] = unknown[at(i)] >= 0 || i == 0;
  }
  // A chain that starts at a tile no pair reached stands where the stage put that tile: known to the stage's
  // uncertainty, never exactly (only the first tile is the origin by definition).
  const Eigen::Vector2d fallback =
      unregistered_sigma_px.minCoeff() >= 0.0 ? unregistered_sigma_px : Eigen::Vector2d::Constant(stage_sigma_px);
  const auto add_anchor = [&] {
    for (int i = 0; i < n; ++i) {
      if (out.anchor[at(i)] == 0) continue;
      out.sigma_px[at(i)] = (out.sigma_px[at(i)].array().square() + fallback.array().square()).sqrt();
    }
  };
  if (m == 0) {
    add_anchor();
    return out;
  }
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
  add_anchor();
  return out;
}

namespace {

// one(k) for every k in [0, count): on OpenCV's pool, or in turn.
void ForEach(int count, bool parallel, const std::function<void(int)>& one) {
  const auto range_of = [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) one(k);
  };
  if (parallel) {
    cv::parallel_for_(cv::Range(0, count), range_of);
  } else {
    range_of(cv::Range(0, count));
  }
}

// The first pass over pairs whose tiles (a, b) are set, each in its own slot, so the result does not depend on the
// thread count: the nominal overlap checked against the whole plausible range `wide` (RegisterPairOverRange; the
// nominal overlap alone for whole frames), or for a thin one the widened search within `window` at once.
void RegisterFirstPass(const std::vector<TileImage>& images, const std::vector<Eigen::Vector2d>& nominal,
                       std::vector<PairRegistration>& pairs, const Eigen::Vector2d& window, const Eigen::Vector2d& wide,
                       const RegistrationOptions& options, const std::function<void(int done, int total)>& on_pair_registered) {
  std::atomic<int> registered{0};
  const int total = static_cast<int>(pairs.size());
  ForEach(total, options.parallel, [&](int k) {
    PairRegistration& pair = pairs[static_cast<size_t>(k)];
    const size_t a = static_cast<size_t>(pair.a), b = static_cast<size_t>(pair.b);
    const Eigen::Vector2d nominal_px = nominal[b] - nominal[a];
    const Eigen::Vector2d overlap(static_cast<double>(images[a].cols()) - std::abs(nominal_px.x()),
                                  static_cast<double>(images[a].rows()) - std::abs(nominal_px.y()));
    if (overlap.minCoeff() < kThinOverlapPx) {
      pair = SearchPair(images[a], images[b], nominal_px, window, options);
    } else if (options.crop_to_overlap) {
      pair = RegisterPairOverRange(images[a], images[b], nominal_px, wide, options);
    } else {
      pair = RegisterPair(images[a], images[b], nominal_px, options);
    }
    pair.a = static_cast<int>(a);
    pair.b = static_cast<int>(b);
    if (on_pair_registered) on_pair_registered(++registered, total);
  });
}

// The listed pairs searched again, widened, within `window` of `centre(pair)` (in parallel); `judge(first,
// second)` may refuse the second result and says why a pair still fails. Each keeps the stage's nominal offset.
void SearchAgain(const std::vector<TileImage>& images, std::vector<PairRegistration>& pairs, const std::vector<int>& again,
                 const std::function<Eigen::Vector2d(const PairRegistration&)>& centre, const Eigen::Vector2d& window,
                 const RegistrationOptions& options,
                 const std::function<void(const PairRegistration&, PairRegistration&)>& judge) {
  std::vector<PairRegistration> second(again.size());
  ForEach(static_cast<int>(again.size()), options.parallel, [&](int j) {
    const PairRegistration& first = pairs[static_cast<size_t>(again[static_cast<size_t>(j)])];
    PairRegistration& pair = second[static_cast<size_t>(j)];
    pair = SearchPair(images[static_cast<size_t>(first.a)], images[static_cast<size_t>(first.b)], centre(first), window, options);
    pair.a = first.a;
    pair.b = first.b;
    judge(first, pair);
  });
  for (size_t j = 0; j < again.size(); ++j) {
    PairRegistration& pair = pairs[static_cast<size_t>(again[j])];
    second[j].nominal_px = pair.nominal_px;  // the stage's, as for every pair; the search window says the rest
    pair = second[j];
  }
}

// Rejected pairs: searched again within the first window around their nominal offsets.
int SearchFailedAgain(const std::vector<TileImage>& images, std::vector<PairRegistration>& pairs,
                      const Eigen::Vector2d& window, const RegistrationOptions& options) {
  std::vector<int> again;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!pairs[k].accepted && !pairs[k].unmoved) again.push_back(static_cast<int>(k));
  }
  SearchAgain(images, pairs, again, [](const PairRegistration& first) { return first.nominal_px; }, window, options,
              [](const PairRegistration& first, PairRegistration& pair) {
                if (!pair.accepted) pair.rejection = first.rejection + "; searched, widened: " + pair.rejection;
              });
  return static_cast<int>(again.size());
}

Eigen::Vector2d FirstWindow(const std::vector<TileImage>& images, const RegistrationOptions& options) {
  return options.search_fraction *
         Eigen::Vector2d(static_cast<double>(images.front().cols()), static_cast<double>(images.front().rows()));
}

// The whole plausible range of a pair's offset about its nominal one (RegistrationOptions::wide_search_fraction).
Eigen::Vector2d WideWindow(const std::vector<TileImage>& images, const RegistrationOptions& options) {
  return options.wide_search_fraction *
         Eigen::Vector2d(static_cast<double>(images.front().cols()), static_cast<double>(images.front().rows()));
}

// Pairs the first window left rejected, searched again over the whole plausible range (when it is wider).
int SearchFailedOverWideRange(const std::vector<TileImage>& images, std::vector<PairRegistration>& pairs,
                              const RegistrationOptions& options) {
  if (!(options.wide_search_fraction > options.search_fraction)) return 0;
  return SearchFailedAgain(images, pairs, WideWindow(images, options), options);
}

// The stage model from the accepted pairs that were no choice between repeats of a pattern; from all accepted
// ones when every one was ambiguous.
TileGridSteps EstimateFromUnambiguous(const std::vector<GridTile>& tiles, std::vector<PairRegistration> pairs) {
  const bool any_clear = std::any_of(pairs.begin(), pairs.end(), [](const auto& p) { return p.accepted && !p.ambiguous; });
  if (any_clear) {
    for (auto& pair : pairs) pair.accepted = pair.accepted && !pair.ambiguous;
  }
  return EstimateTileGridSteps(tiles, pairs);
}

// The spread (rms per axis, about their mean) of the placed tiles' positions about their stage positions, over the
// tiles placed from the first one by images along both axes; none with fewer than three.
std::optional<Eigen::Vector2d> StageSpread(const TilePositions& positions, const std::vector<Eigen::Vector2d>& stage_px) {
  std::vector<Eigen::Vector2d> off;
  for (size_t i = 1; i < stage_px.size(); ++i) {
    // Only tiles the images place along both axes: along machining marks a tile is wherever the loose prior let it.
    if (positions.anchor[i] == 0 && positions.registered[i] && positions.sigma_px[i].maxCoeff() < 1.0) {
      off.push_back(positions.positions_px[i] - stage_px[i]);
    }
  }
  if (off.size() < 3) return std::nullopt;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero(), square = Eigen::Vector2d::Zero();
  for (const auto& d : off) mean += d / static_cast<double>(off.size());
  for (const auto& d : off) square += (d - mean).cwiseAbs2() / static_cast<double>(off.size() - 1);
  return square.cwiseSqrt();
}

// A stage steps along its scan axis by its encoders: a right neighbour's x step and a lower neighbour's y step vary by
// the overlaps' spread (a few pixels), however far the rows or columns sit sideways (tens of pixels, which the loops
// judge). A pair whose offset along its step lies farther from the median step of its direction than 5 robust
// standard deviations of those steps, and than the first search's window along it (`window`: the uncertainty the
// declared overlap leaves; the steps of one row boundary are all alike, so their spread alone may be nil), took a
// repeat of a line pattern: parallel traces
// or edges fix the step's axis locally and match a neighbour line as well as the true one (issue 42's sparse cut
// tiles of a printed circuit board: a pair 37 px short of a 230 px step, quality 0.71, that no loop saw, its other
// direction and its tile's other pair fixing one direction each). Such a pair is refused: it places nothing, the
// loops may still find it where the other pairs put it, and a tile that hangs on it lands by the stage prior with the
// stage's spread as its uncertainty. Needs TileGridSteps::kMinPairs steps of the direction whose information fixes
// the step's axis to half a pixel; returns the pairs refused.
int RefuseStepOutliers(const std::vector<GridTile>& tiles, std::vector<PairRegistration>& pairs, const Eigen::Vector2d& window) {
  int refused = 0;
  for (const int axis : {0, 1}) {  // 0: right neighbours, their x step; 1: lower ones, their y step
    const auto of_direction = [&](const PairRegistration& pair) {
      const GridTile& a = tiles[static_cast<size_t>(pair.a)];
      const GridTile& b = tiles[static_cast<size_t>(pair.b)];
      return axis == 0 ? (b.col - a.col == 1 && b.row == a.row) : (b.row - a.row == 1 && b.col == a.col);
    };
    const auto step = [&](const PairRegistration& pair) {
      return pair.offset_px(axis) - (tiles[static_cast<size_t>(pair.b)].nominal_px - tiles[static_cast<size_t>(pair.a)].nominal_px)(axis);
    };
    std::vector<double> steps;
    for (const auto& pair : pairs) {
      if (pair.accepted && !pair.ambiguous && of_direction(pair) && pair.information(axis, axis) > 4.0) steps.push_back(step(pair));
    }
    if (static_cast<int>(steps.size()) < TileGridSteps::kMinPairs) continue;
    const double median = HighMedian(steps);
    for (auto& d : steps) d = std::abs(d - median);
    const double tolerance = std::max(window(axis), 5.0 * 1.4826 * HighMedian(steps) + 1.0);
    for (auto& pair : pairs) {
      if (!pair.accepted || !of_direction(pair) || !(std::abs(step(pair) - median) > tolerance)) continue;
      pair.accepted = false;
      char text[200];
      std::snprintf(text, sizeof text, "its step lies %.1f px from the grid's median step along its scan axis, beyond the "
                    "steps' tolerance of %.1f px: a repeat of a line pattern, refused", step(pair) - median, tolerance);
      pair.rejection = text;
      ++refused;
    }
  }
  return refused;
}

}  // namespace

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
  RegistrationResult result;
  std::vector<Eigen::Vector2d> nominal;
  for (const auto& tile : tiles) nominal.push_back(tile.nominal_px);
  for (const auto& [a, b] : GridNeighbourPairs(tiles)) {
    PairRegistration pair;
    pair.a = a;
    pair.b = b;
    result.pairs.push_back(pair);
  }
  const Eigen::Vector2d first_window = FirstWindow(images, options);
  RegisterFirstPass(images, nominal, result.pairs, first_window, WideWindow(images, options), options, on_pair_registered);

  // The stage from the pairs the first pass accepted; with it, the pairs that failed or disagree are searched
  // again, widened, within a few repeatabilities of the model's offset (the constrained second search of MIST [Chalfoun
  // 2017]). When too few pairs passed to estimate one, the failed ones are first searched within
  // options.search_fraction of the tile around their nominal offsets, and the model is estimated from what then stands.
  result.stage = EstimateFromUnambiguous(tiles, result.pairs);
  // Whole frames (crop_to_overlap false, the benchmark's baseline) have no overlap to widen: a second search
  // correlates the same frames again, and only the first pass stands.
  const bool search_again = options.crop_to_overlap;
  const Eigen::Vector2d wide_window = WideWindow(images, options);
  if (search_again && !result.stage.Any()) {
    result.pairs_searched_again += SearchFailedAgain(images, result.pairs, first_window, options);
    result.stage = EstimateFromUnambiguous(tiles, result.pairs);
  }
  if (search_again && !result.stage.Any()) {
    // Still too few to learn the stage from: the steps may be farther off than the first window reaches.
    SearchFailedOverWideRange(images, result.pairs, options);
    result.stage = EstimateFromUnambiguous(tiles, result.pairs);
  }
  if (search_again && result.stage.Any()) {
    const TileGridSteps& model = result.stage;
    // A stage that repeats worse than the first window (steps tens of pixels apart) is searched as widely as its
    // repeatability says, up to the plausible range.
    const Eigen::Vector2d tolerance = model.Tolerance(first_window).cwiseMin(wide_window);
    const auto predicted = [&](const PairRegistration& pair) {
      const GridTile& a = tiles[static_cast<size_t>(pair.a)];
      const GridTile& b = tiles[static_cast<size_t>(pair.b)];
      return Eigen::Vector2d(b.nominal_px - a.nominal_px + model.Correction(b.row - a.row, b.col - a.col));
    };
    const auto disagreement = [&](const PairRegistration& pair) {
      return ((pair.offset_px - predicted(pair)).cwiseAbs() - tolerance).maxCoeff();
    };
    std::vector<int> again;
    for (size_t k = 0; k < result.pairs.size(); ++k) {
      const PairRegistration& pair = result.pairs[k];
      // An ambiguous pair chose by the nominal offset; the model, learnt from the clear pairs, chooses again.
      if (pair.unmoved) continue;  // no search registers tiles that show no motion
      if (!pair.accepted || disagreement(pair) > 0.0 || pair.ambiguous) again.push_back(static_cast<int>(k));
    }
    result.pairs_searched_again += static_cast<int>(again.size());
    SearchAgain(images, result.pairs, again, predicted, tolerance, options, [&](const PairRegistration& first, PairRegistration& pair) {
      // The model is a prior, not a verdict: a stage whose rows or columns sit sideways by more than its
      // repeatability shows (a backlash per row) makes right pairs disagree with it. A pair that registers stands,
      // and the loops of the grid judge it (CheckPairsAgainstLoops): the search near the model's offset where it
      // registers, unless the first match was clearly better; the first match where the search found nothing.
      if (pair.accepted && !(first.accepted && first.quality > pair.quality + options.ambiguous_ncc)) return;
      if (first.accepted) {
        pair = first;
        return;
      }
      pair.rejection = first.rejection + "; searched again within the stage model's tolerance: " + pair.rejection;
    });
    // Those that still fail, over the whole plausible range about the nominal offset: a stage whose columns sit
    // apart by more than a thin overlap's window (and than its model's repeatability says) puts a sparse pair there,
    // where no nominal overlap held enough texture to find it. What these find, the loops judge.
    result.pairs_searched_again += SearchFailedOverWideRange(images, result.pairs, options);
    // Estimated again from every pair that now stands.
    if (!again.empty()) result.stage = EstimateFromUnambiguous(tiles, result.pairs);
  }
  const TileGridSteps& model = result.stage;
  for (size_t i = 0; i < tiles.size(); ++i) {
    result.stage_positions_px.push_back(
        nominal[i] + model.Correction(tiles[i].row - tiles[0].row, tiles[i].col - tiles[0].col));
  }
  const Eigen::Vector2d& repeatability = model.repeatability_px;
  result.stage_sigma_px = repeatability.minCoeff() > 0.0 ? repeatability.maxCoeff() : options.stage_sigma_px;
  // A tile no pair registers could be anywhere the search looked: uniform over the plausible range (the stage's
  // declared sigma at least). Not the model's repeatability: the pairs it comes from are the ones that registered,
  // and a stage whose rows or columns sit apart puts the others farther off than they show (issue 42's cut tiles:
  // 35 px off with a repeatability of 1.2 px).
  const Eigen::Vector2d unregistered = (wide_window / std::sqrt(3.0)).cwiseMax(options.stage_sigma_px);
  // The loops decide between a pair and the rest of the grid: a pair they contradict is searched again where they
  // put it, or dropped; then their misclosures scale what the pairs claim.
  if (search_again) RefuseStepOutliers(tiles, result.pairs, first_window);
  LoopCheckOptions loop_options;
  loop_options.ambiguous_ncc = options.ambiguous_ncc;
  const auto research = [&](const PairRegistration& pair, const Eigen::Vector2d& predicted, const Eigen::Vector2d& window) {
    return SearchPair(images[static_cast<size_t>(pair.a)], images[static_cast<size_t>(pair.b)], predicted,
                      window.cwiseMin(wide_window), options);
  };
  // The stage there only as loosely as the plausible range: the loops of pairs overrule a pair, the stage model
  // alone does not (its repeatability, from the spread of the pairs, misses a stage whose rows sit apart).
  const double loose_stage_px = wide_window.maxCoeff() / std::sqrt(3.0);
  result.loops = CheckPairsAgainstLoops(result.stage_positions_px, std::max(result.stage_sigma_px, loose_stage_px),
                                        result.pairs, research, loop_options);
  for (const auto& pair : result.pairs) result.pairs_unresolved += !pair.accepted;
  // The stage prior as loose as the placed tiles show the stage to be (their spread about the model), where the
  // model's repeatability, from the spread of the pairs about the mean step, says less: a stage whose rows sit apart
  // by 20 px has pairs that agree with each other row by row, and a prior of a pixel would pull every tile.
  // The pairs weighed as the loops show them (the Birge ratio; the pairs keep their own claims), and no pair better
  // than the systematic floor of a pair's registration (detail::kSystematicPx, the rms error of noise-light
  // synthetic pairs: Lanczos resampling, remnants of the shading), which the loops' scale must not take away: a
  // loop misclosure sees each pair's noise, not what shifts every pair of a tile alike (on issue 42's cut real tiles
  // a tile 0.04 px off claimed 0.009 px without a floor).
  std::vector<PairRegistration> weighed = result.pairs;
  for (auto& pair : weighed) {
    const Eigen::Matrix2d w = pair.information / (result.loops.uncertainty_scale * result.loops.uncertainty_scale);
    const Eigen::Matrix2d floored =
        w * (Eigen::Matrix2d::Identity() + detail::kSystematicPx * detail::kSystematicPx * w).inverse();
    pair.information = 0.5 * (floored + floored.transpose());
  }
  const TilePositions loose = SolveTilePositions(result.stage_positions_px, weighed, loose_stage_px, unregistered);
  // Where too few tiles are placed from the first one to show the stage's spread (sparse content: the pairs that
  // register fix one direction each, along edges and traces), nothing vouches for the model's positions closer than
  // the plausible range: the model's repeatability comes from the pairs that registered, not from the tiles that
  // rest on it (issue 42's sparse cut tiles of a circuit board: a block of tiles 59 px off a model learnt from
  // sideways drifts that differ column by column, where the model's repeatability said 5 px). A tile that rests on
  // the prior along a direction then carries that range as its uncertainty. The stage's declared sigma, where the
  // pairs gave no repeatability (machining marks: no pair fixes the axis along them), stands as declared.
  const std::optional<Eigen::Vector2d> spread = StageSpread(loose, result.stage_positions_px);
  if (spread) {
    result.stage_sigma_px = std::max(result.stage_sigma_px, spread->maxCoeff());
  } else if (repeatability.minCoeff() > 0.0) {
    result.stage_sigma_px = std::max(result.stage_sigma_px, loose_stage_px);
  }
  // The positions with the stage's error shared along rows and columns (grid_position_solve.h), its spreads from
  // every pair that now stands: a tile that hangs on a pair fixing one direction lands along the other where the
  // tiles of its row and column put it, and says what the stage leaves. Where the pairs show no spread, the plausible
  // range for the steps; along an axis no pair fixes, the prior above for each tile on its own.
  const TileGridSteps shared = EstimateFromUnambiguous(tiles, result.pairs);
  result.stage_axes = StageAxesPriorOf(shared, loose_stage_px, result.stage_sigma_px);
  result.positions = SolveGridPositions(tiles, result.stage_positions_px, weighed, result.stage_axes, loose_stage_px);
  return result;
}

}  // namespace fvm::imaging

namespace fvm::imaging {

ChainRegistration RegisterTileChain(const std::vector<TileImage>& images, const std::vector<Eigen::Vector2d>& nominal_px,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered) {
  if (images.size() != nominal_px.size()) throw std::invalid_argument("RegisterTileChain: one image per tile");
  if (images.size() < 2) throw std::invalid_argument("RegisterTileChain: a chain needs two tiles or more");
  options.Check();
  ChainRegistration result;
  for (size_t k = 0; k + 1 < images.size(); ++k) {
    PairRegistration pair;
    pair.a = static_cast<int>(k);
    pair.b = static_cast<int>(k + 1);
    result.pairs.push_back(pair);
  }
  const Eigen::Vector2d first_window = FirstWindow(images, options);
  RegisterFirstPass(images, nominal_px, result.pairs, first_window, WideWindow(images, options), options,
                    on_pair_registered);
  if (options.crop_to_overlap) {
    result.pairs_searched_again = SearchFailedAgain(images, result.pairs, first_window, options);
    SearchFailedOverWideRange(images, result.pairs, options);
  }
  result.positions = SolveTilePositions(nominal_px, result.pairs, options.stage_sigma_px);
  return result;
}

}  // namespace fvm::imaging
