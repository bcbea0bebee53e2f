// Tile grids cut from real images at known positions (tests/support/cut_tiles.h), so that the truth is exact on real
// texture (issue 42): thin overlaps, a stage that puts rows and columns sideways by more than the overlap, sparse
// content on a flat background, vignetting and exposure. Judged by the positions against the truth (to the pixel),
// by the pairs whose overlap the positions lose, and by the standardised errors of the stated uncertainties.
// Skipped where ../shared is absent.

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "imaging/overlap_correlation.h"
#include "imaging/tile_registration.h"
#include "tests/support/cut_tiles.h"

namespace fvm::imaging {
namespace {

struct CutSet {
  std::string name;
  const TileImage* source;
  testing::CutTileOptions options;
};

struct Judged {
  double rms_px = 0.0, max_px = 0.0;
  int lost = 0, registered = 0;
  int lost_accepted = 0;  // lost pairs the registration used (the others it refused, and said so)
  std::vector<double> z;  // standardised errors, both axes of every tile placed from the first
  std::vector<double> z_unplaced;  // the same of the tiles no pair links to the first
};

// Positions against the truth over the tiles placed from the first one (after their common offset), the
// standardised errors against the first tile, and the pairs whose overlap the positions lose: the truth's overlap
// correlates (>= 0.5) and the positions' does not (< 0.3).
Judged Judge(const testing::CutTiles& cut, const RegistrationResult& result) {
  Judged out;
  const TilePositions& p = result.positions;
  // The largest group of tiles the pairs link (the first tile's, unless it has no good neighbour).
  std::vector<int> members(cut.truth_px.size(), 0);
  for (const int a : p.anchor) ++members[static_cast<size_t>(a)];
  const int largest = static_cast<int>(std::max_element(members.begin(), members.end()) - members.begin());
  // Of those, the ones whose stated uncertainty claims the pixel (a tile hanging on a pair that fixes one axis only,
  // along sparse edges, says u = 2 px and is judged by its standardised error alone).
  // (A group anchored elsewhere than the first tile carries its anchor's stage spread in every u, added in
  // quadrature: what is left is the tile's u relative to the anchor.)
  const Eigen::Vector2d anchor_u = p.sigma_px[static_cast<size_t>(largest)];
  std::vector<size_t> placed;
  for (size_t i = 0; i < cut.truth_px.size(); ++i) {
    const Eigen::Vector2d relative_u = (p.sigma_px[i].array().square() - anchor_u.array().square()).max(0.0).sqrt();
    if (p.anchor[i] == largest && relative_u.maxCoeff() < 1.0) placed.push_back(i);
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const size_t i : placed) mean += (p.positions_px[i] - cut.truth_px[i]) / static_cast<double>(placed.size());
  double sum = 0.0;
  for (const size_t i : placed) {
    const Eigen::Vector2d e = p.positions_px[i] - cut.truth_px[i] - mean;
    sum += e.squaredNorm();
    out.max_px = std::max(out.max_px, e.norm());
  }
  out.rms_px = std::sqrt(sum / static_cast<double>(placed.size()));
  for (size_t i = 1; i < cut.truth_px.size(); ++i) {
    out.registered += p.registered[i];
    const Eigen::Vector2d e = p.positions_px[i] - cut.truth_px[i];
    auto& z = p.anchor[i] == 0 ? out.z : out.z_unplaced;
    for (int k = 0; k < 2; ++k) z.push_back(e(k) / p.sigma_px[i](k));
  }
  out.registered += 1;
  const auto truth = NeighbourOverlapNcc(cut.images, cut.tiles, cut.truth_px);
  const auto ours = NeighbourOverlapNcc(cut.images, cut.tiles, p.positions_px);
  for (size_t k = 0; k < truth.size(); ++k) {
    if (truth[k].correlation.ncc >= 0.5 && !(ours[k].correlation.ncc >= 0.3)) {
      ++out.lost;
      out.lost_accepted += result.pairs[k].accepted;
      if (std::getenv("CUT_DEBUG")) {
        std::printf("  lost %d-%d: truth ncc %.3f (%d px), ours %.3f (%d px) at %.2f %.2f\n", truth[k].a, truth[k].b,
                    truth[k].correlation.ncc, truth[k].correlation.pixels, ours[k].correlation.ncc, ours[k].correlation.pixels,
                    (p.positions_px[static_cast<size_t>(truth[k].b)] - p.positions_px[static_cast<size_t>(truth[k].a)]).x(),
                    (p.positions_px[static_cast<size_t>(truth[k].b)] - p.positions_px[static_cast<size_t>(truth[k].a)]).y());
      }
    }
  }
  return out;
}

// Three seeds of each source, dense and sparse, the stage's sideways jitter 5, 12 and 20 px (on overlaps of 11-15 px;
// one set of 9-20 px, 5-8 % of a tile): a dozen grids, about ten seconds.
std::vector<CutSet> Sets(const TileImage& confocal, const TileImage& strip) {
  std::vector<CutSet> sets;
  const double jitters[] = {5.0, 12.0, 20.0};
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    testing::CutTileOptions o;
    o.seed = seed;
    o.jitter_px = jitters[seed - 1];
    if (confocal.size() > 0) {
      sets.push_back({"confocal", &confocal, o});
      testing::CutTileOptions sparse = o;
      sparse.sparse_fraction = 0.35;
      sparse.seed = seed + 10;
      sets.push_back({"confocal sparse", &confocal, sparse});
    }
    if (strip.size() > 0) {
      o.cols = 5;
      if (seed == 2) o.min_overlap_px = 9, o.max_overlap_px = 20;
      sets.push_back({"starrynight", &strip, o});
      testing::CutTileOptions sparse = o;
      sparse.sparse_fraction = 0.4;
      sparse.seed = seed + 10;
      sets.push_back({"starrynight sparse", &strip, sparse});
    }
  }
  return sets;
}

TEST(CutTileGrid, RealTexturePlacedToThePixelWithHonestUncertainty) {
  TileImage confocal = testing::ConfocalSource();
  TileImage strip = testing::StarrynightSource();
  // CUT_SOURCE=IMAGE: the same sets cut from another real image (a texture the registration was never tried on);
  // the sets keep their names, which then say only the grid's shape (4 or 5 columns) and density.
  if (const char* other = std::getenv("CUT_SOURCE")) confocal = strip = ReadTileImage(other);
  if (confocal.size() == 0 && strip.size() == 0) GTEST_SKIP() << "../shared/realdata absent";
  std::printf("sources: confocal %ld x %ld, strip %ld x %ld\n", confocal.cols(), confocal.rows(), strip.cols(), strip.rows());
  std::vector<double> z, z_unplaced;
  for (const CutSet& set : Sets(confocal, strip)) {
    const testing::CutTiles cut = testing::CutTileGrid(*set.source, set.options);
    const RegistrationResult result = RegisterTileGrid(cut.images, cut.tiles, RegistrationOptions{});
    const Judged judged = Judge(cut, result);
    double zz = 0.0, zmax = 0.0;
    for (const double v : judged.z) zz += v * v, zmax = std::max(zmax, std::abs(v));
    std::printf("%-20s seed %2u jitter %4.1f: rms %.2f px (max %.2f), %d lost, %d of %zu registered, %zu of %zu "
                "pairs accepted, %zu overruled, Birge %.2f, z rms %.2f max %.2f\n",
                set.name.c_str(), set.options.seed, set.options.jitter_px, judged.rms_px, judged.max_px, judged.lost,
                judged.registered, cut.images.size(), result.pairs.size() - result.pairs_unresolved,
                result.pairs.size(), result.loops.overruled.size(), result.loops.birge_ratio,
                std::sqrt(zz / judged.z.size()), zmax);
    if (std::getenv("CUT_DEBUG")) {
      for (const auto& pair : result.pairs) {
        const Eigen::Vector2d truth = cut.truth_px[pair.b] - cut.truth_px[pair.a];
        std::printf("  %2d-%2d acc %d amb %d srch %d q %.3f off %7.2f %7.2f truth %7.1f %7.1f nominal %7.1f %7.1f u %.3f %s\n",
                    pair.a, pair.b, pair.accepted, pair.ambiguous, pair.searched, pair.quality, pair.offset_px.x(),
                    pair.offset_px.y(), truth.x(), truth.y(), pair.nominal_px.x(), pair.nominal_px.y(),
                    pair.accepted ? std::sqrt(pair.information.inverse().maxCoeff()) : 0.0, pair.rejection.c_str());
        if (pair.accepted) std::printf("      info %.3g %.3g %.3g ncand %zu\n", pair.information(0,0), pair.information(0,1), pair.information(1,1), pair.candidates.size());
        for (const auto& c : pair.candidates) std::printf("      cand %.2f %.2f ncc %.3f\n", c.offset_px.x(), c.offset_px.y(), c.ncc);
      }
      for (size_t i = 0; i < cut.truth_px.size(); ++i) {
        const Eigen::Vector2d e = result.positions.positions_px[i] - cut.truth_px[i];
        std::printf("  tile %2zu err %7.2f %7.2f u %.3f %.3f reg %d\n", i, e.x(), e.y(), result.positions.sigma_px[i].x(),
                    result.positions.sigma_px[i].y(), static_cast<int>(result.positions.registered[i]));
      }
    }
    EXPECT_LE(judged.rms_px, 1.0) << set.name << " seed " << set.options.seed;
    // No pair is lost on whole scenes; on sparse ones only pairs the registration refused (an overlap holding the
    // soft edge of a patch, no texture standing out of the noise), whose tiles then say the stage's spread.
    if (set.options.sparse_fraction == 0.0) {
      EXPECT_EQ(judged.lost, 0) << set.name << " seed " << set.options.seed;
    }
    EXPECT_EQ(judged.lost_accepted, 0) << set.name << " seed " << set.options.seed;
    z.insert(z.end(), judged.z.begin(), judged.z.end());
    z_unplaced.insert(z_unplaced.end(), judged.z_unplaced.begin(), judged.z_unplaced.end());
  }
  double zz = 0.0, zmax = 0.0;
  for (const double v : z) zz += v * v, zmax = std::max(zmax, std::abs(v));
  const double z_rms = std::sqrt(zz / static_cast<double>(z.size()));
  double uu = 0.0, umax = 0.0;
  for (const double v : z_unplaced) uu += v * v, umax = std::max(umax, std::abs(v));
  std::printf("standardised errors over every set: rms %.2f, max %.2f (%zu); of the tiles no pair links to the first: "
              "rms %.2f, max %.2f (%zu)\n",
              z_rms, zmax, z.size(), std::sqrt(uu / static_cast<double>(z_unplaced.size())), umax, z_unplaced.size());
  EXPECT_GE(z_rms, 0.8);
  EXPECT_LE(z_rms, 1.25);
  EXPECT_LT(zmax, 4.0);
  // A tile no pair links to the first stands where the stage's rows and columns put it, with the stage's spread as
  // its u: as honest as the others (too few to judge an rms on their own; none beyond 4, none so loose that all
  // lie within half a u).
  for (const double v : z_unplaced) EXPECT_LT(std::abs(v), 4.0);
  if (!z_unplaced.empty()) {
    EXPECT_GT(umax, 0.5);
  }
}


// A repeat planted in two tiles (issue 42): a patch of real texture, its contrast raised, pasted into the overlap of
// one vertical pair in the upper tile and into the lower tile `sideways_px` to the side of where the truth puts it.
// The pair's best match is then the patch on itself, sideways_px off the truth, and stands out more than the scene's
// true overlap; the stage allows it (the stage model tolerates the rows' sideways jitter). The three other pairs
// around each square, and the stage, say otherwise: the loops must overrule the pair, and the lower tile must land
// where the truth is, with a standardised error that says so.
testing::CutTiles PlantRepeat(testing::CutTiles cut, int upper, int lower, int sideways_px, double contrast) {
  const Eigen::Vector2i truth = (cut.truth_px[static_cast<size_t>(lower)] - cut.truth_px[static_cast<size_t>(upper)])
                                    .array()
                                    .round()
                                    .cast<int>();
  TileImage& a = cut.images[static_cast<size_t>(upper)];
  TileImage& b = cut.images[static_cast<size_t>(lower)];
  const int overlap = static_cast<int>(a.rows()) - truth.y();
  // The patch: real texture from the middle of the first tile, as thin as the overlap, half the tile wide.
  const int rows = overlap - 2, cols = static_cast<int>(a.cols()) / 2;
  const TileImage& source = cut.images.front();
  Eigen::MatrixXf patch = source.block((source.rows() - rows) / 2, (source.cols() - cols) / 2, rows, cols);
  const float mean = patch.mean();
  patch = (patch.array() - mean) * static_cast<float>(contrast) + mean;
  // In a: inside the overlap, left of the middle. In b: where a's pixel (x, y) lands at the wrong offset truth + d.
  const int ya = static_cast<int>(a.rows()) - overlap + 1, xa = static_cast<int>(a.cols()) / 2 - cols / 2 - 10;
  const int xb = xa - truth.x() - sideways_px, yb = ya - truth.y();
  a.block(ya, xa, rows, cols) = patch;
  b.block(yb, xb, rows, cols) = patch;
  return cut;
}

TEST(CutTileGrid, LoopsOverruleARepeatPlantedInTwoTiles) {
  const TileImage confocal = testing::ConfocalSource();
  if (confocal.size() == 0) GTEST_SKIP() << "../shared/realdata absent";
  // Seeds whose overlaps leave the plant rows enough to outmatch the scene (seed 2's 11-row overlap leaves 9, and the
  // pair rejects both places): the test asserts that the pair took the repeat, so a case that stops being one fails.
  for (const uint32_t seed : {1u, 3u, 4u, 5u}) {
    testing::CutTileOptions o;
    o.seed = seed;
    o.jitter_px = 5.0;
    const int cols = o.cols, upper = 1 * cols + 1, lower = 2 * cols + 1;  // an inner pair: loops on both sides
    const int sideways = 12;
    const testing::CutTiles cut = PlantRepeat(testing::CutTileGrid(confocal, o), upper, lower, sideways, 4.0);
    const RegistrationResult result = RegisterTileGrid(cut.images, cut.tiles, RegistrationOptions{});
    const Judged judged = Judge(cut, result);
    size_t pair = 0;
    while (pair < result.pairs.size() && !(result.pairs[pair].a == upper && result.pairs[pair].b == lower)) ++pair;
    ASSERT_LT(pair, result.pairs.size());
    const Eigen::Vector2d truth = cut.truth_px[static_cast<size_t>(lower)] - cut.truth_px[static_cast<size_t>(upper)];
    double zmax = 0.0;
    for (const double v : judged.z) zmax = std::max(zmax, std::abs(v));
    const auto overruled = std::find_if(result.loops.overruled.begin(), result.loops.overruled.end(),
                                        [&](const OverruledPair& r) { return r.pair == static_cast<int>(pair); });
    std::printf("planted repeat, seed %u: %zu overruled%s; rms %.2f px (max %.2f), %d lost, z max %.2f; the pair: "
                "%s, %.2f %.2f (truth %.0f %.0f)\n",
                seed, result.loops.overruled.size(),
                overruled == result.loops.overruled.end() ? "" : (" (" + overruled->Text() + ")").c_str(),
                judged.rms_px, judged.max_px, judged.lost, zmax, result.pairs[pair].accepted ? "accepted" : "dropped",
                result.pairs[pair].offset_px.x(), result.pairs[pair].offset_px.y(), truth.x(), truth.y());
    // The pair alone took the repeat: what it registered lay the planted distance off the truth.
    ASSERT_NE(overruled, result.loops.overruled.end())
        << "seed " << seed << ": not overruled; the pair " << (result.pairs[pair].accepted ? "stands" : "was refused")
        << " at " << result.pairs[pair].offset_px.transpose() << " " << result.pairs[pair].rejection;
    EXPECT_GT((overruled->registered_px - truth).norm(), sideways - 2.0) << "seed " << seed;
    // The loops put it back: the prediction near the truth, and every tile within a pixel of it.
    EXPECT_LT((overruled->predicted_px - truth).norm(), 1.0) << "seed " << seed;
    if (result.pairs[pair].accepted) {
      EXPECT_LT((result.pairs[pair].offset_px - truth).norm(), 1.0) << "seed " << seed;
    }
    EXPECT_LE(judged.max_px, 1.0) << "seed " << seed;
    EXPECT_EQ(judged.registered, static_cast<int>(cut.images.size())) << "seed " << seed;
    // Honest u: no tile's error beyond 4 of its standard uncertainties (the bound of the grids above).
    EXPECT_LT(zmax, 4.0) << "seed " << seed;
  }
}

// The sparse sets cut from a printed circuit board (../shared/realdata/focus/pcb/expected.jpg, 2048 x 1536 px), a
// texture of parallel traces and edges the registration was never tuned on: an overlap there often fixes one
// direction only, and a trace beside the true one matches as well as it (issue 42). Seed 11 (5 columns) had pair
// 5-6 accepted 37 px short of its 232 px step, quality 0.71, one tile 37 px off; seed 13 (4 columns) had pairs 2-3
// and 6-7 35-40 px short. Such a pair must be refused (it places nothing), no accepted pair may sit off the truth
// along a direction its information fixes, and the tiles that hang on the stage prior must say so in their u.
TEST(CutTileGrid, LineTextureRefusesRepeatsOfItsTraces) {
  const std::filesystem::path file = std::filesystem::path(FVM_REALDATA_DIR) / "focus" / "pcb" / "expected.jpg";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "../shared/realdata absent";
  const TileImage pcb = ReadTileImage(file);
  struct Case {
    uint32_t seed;
    int cols;
    double jitter_px;
    double sparse_fraction;
    std::vector<std::pair<int, int>> refused;  // the pairs that took a neighbouring trace
  };
  // And the whole board, seed 2: pair 9-13 (an 11-row overlap whose texture lies in b's first column) read an overlap
  // NCC of 0.30 at positions 0.03 px from the truth (0.56 at it), counted lost: the measure dropped the column.
  for (const Case& c : {Case{11, 5, 5.0, 0.4, {{5, 6}, {12, 13}}}, Case{13, 4, 20.0, 0.35, {{2, 3}, {6, 7}}},
                        Case{2, 4, 12.0, 0.0, {}}}) {
    testing::CutTileOptions o;
    o.seed = c.seed;
    o.cols = c.cols;
    o.jitter_px = c.jitter_px;
    o.sparse_fraction = c.sparse_fraction;
    const testing::CutTiles cut = testing::CutTileGrid(pcb, o);
    const RegistrationResult result = RegisterTileGrid(cut.images, cut.tiles, RegistrationOptions{});
    const Judged judged = Judge(cut, result);
    std::printf("pcb %s seed %u, %d columns: rms %.2f px (max %.2f), %d lost (%d accepted), %zu of %zu pairs accepted\n",
                c.sparse_fraction > 0.0 ? "sparse" : "whole", c.seed, c.cols, judged.rms_px, judged.max_px, judged.lost, judged.lost_accepted,
                result.pairs.size() - result.pairs_unresolved, result.pairs.size());
    for (const auto& [a, b] : c.refused) {
      const auto pair = std::find_if(result.pairs.begin(), result.pairs.end(), [&](const auto& p) { return p.a == a && p.b == b; });
      ASSERT_NE(pair, result.pairs.end());
      EXPECT_FALSE(pair->accepted) << "seed " << c.seed << " pair " << a << "-" << b << " at " << pair->offset_px.transpose();
    }
    // Every accepted pair right along the directions its information fixes to a pixel (the cut's truth is exact;
    // 1 px: a whole-pixel mistake, far beyond what any claims there).
    for (const auto& pair : result.pairs) {
      if (!pair.accepted) continue;
      const Eigen::Vector2d error = pair.offset_px - (cut.truth_px[static_cast<size_t>(pair.b)] - cut.truth_px[static_cast<size_t>(pair.a)]);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> directions(pair.information);
      for (int k = 0; k < 2; ++k) {
        if (!(directions.eigenvalues()(k) > 1.0)) continue;  // u above 1 px: a direction the pair leaves open
        EXPECT_LT(std::abs(directions.eigenvectors().col(k).dot(error)), 1.0)
            << "seed " << c.seed << " pair " << pair.a << "-" << pair.b << " at " << pair.offset_px.transpose();
      }
    }
    // The tiles the images place land to the pixel; the others say the stage's spread. Seed 13 had a block of eight
    // tiles (3, 7, 9-11, 13-15) hanging on pair 5-9, which fixes one direction only (a diagonal trace), 59 px off with
    // u = 12 px (z 5.1): the stage's rows and columns, shared with tiles the images place, now put it.
    EXPECT_LE(judged.rms_px, 1.0) << "seed " << c.seed;
    EXPECT_EQ(judged.lost, 0) << "seed " << c.seed;
    for (const double v : judged.z) EXPECT_LT(std::abs(v), 4.0) << "seed " << c.seed;
    for (const double v : judged.z_unplaced) EXPECT_LT(std::abs(v), 4.0) << "seed " << c.seed;
    if (c.seed == 13) {
      // Tile 9 is linked to the first only through 5-9: the images fix one of its directions, so it is no
      // registered tile (the stage decides the other), while tile 5, placed by pairs across both axes, is.
      const auto hanging = std::find_if(result.pairs.begin(), result.pairs.end(), [](const auto& p) { return p.a == 5 && p.b == 9; });
      ASSERT_NE(hanging, result.pairs.end());
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> fixes(hanging->information);
      EXPECT_LT(fixes.eigenvalues()(0), 1.0) << "pair 5-9 no longer leaves a direction open: the case is gone";
      EXPECT_FALSE(result.positions.registered[9]);
      EXPECT_TRUE(result.positions.registered[5]);
      const Eigen::Vector2d error = result.positions.positions_px[9] - cut.truth_px[9];
      EXPECT_LT(error.norm(), 1.0);
    }
  }
}

}  // namespace
}  // namespace fvm::imaging
