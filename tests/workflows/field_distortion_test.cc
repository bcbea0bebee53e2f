// The field distortion identified from the overlaps with the positions (workflows/stitch_distortion.h), on tiles
// rendered through a known field: the field and the positions recovered, the linear part left out by name, and what
// the overlaps cannot determine refused.

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>

#include "artefacts/simulation/tile_synthesis.h"
#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"
#include "workflows/field_distortion_file.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"

namespace fvm::workflows {
namespace {

imaging::FieldDistortion Field(int size, const std::vector<std::pair<std::string, double>>& terms, int order = 3) {
  imaging::FieldDistortion f;
  f.width_px = f.height_px = size;
  f.order = order;
  const std::vector<std::string>& names = imaging::FieldDistortionTermNames(order);
  f.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  for (const auto& [name, value] : terms) {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << name;
    f.coefficients(it - names.begin()) = value;
  }
  return f;
}

// rms of the difference of two fields over the tile (px), on a 17 x 17 grid.
double FieldDifferenceRms(const imaging::FieldDistortion& a, const imaging::FieldDistortion& b) {
  double sum = 0.0;
  int n = 0;
  for (int j = 0; j <= 16; ++j) {
    for (int i = 0; i <= 16; ++i) {
      const Eigen::Vector2d u(i * (a.width_px - 1) / 16.0, j * (a.height_px - 1) / 16.0);
      sum += (a.Displacement(u) - b.Displacement(u)).squaredNorm() / 2.0, ++n;
    }
  }
  return std::sqrt(sum / n);
}

struct DistortedGrid {
  imaging::TileLayout layout;
  std::vector<imaging::TileImage> images;
  std::vector<Eigen::Vector2d> truth_px;  // top-left corners of the undistorted tiles
  double overlap = 0.2;
};

// rows x cols tiles of `size` px, a stage error of 1.5 px per axis, every tile through `field`.
DistortedGrid RenderGrid(int rows, int cols, int size, const imaging::FieldDistortion& field, std::uint64_t seed,
                         bool texture = true) {
  std::mt19937_64 random(seed);
  artefacts::TileCameraOptions camera;
  camera.vignetting = 0.1;
  if (!texture) camera.contrast = 0.0, camera.noise = 0.0;
  const artefacts::TileScene scene(camera, random);
  std::normal_distribution<double> stage(0.0, 1.5);
  DistortedGrid g;
  const int margin = static_cast<int>(std::ceil(field.LargestDisplacementPx())) + 6;
  for (int c = 0; c < cols; ++c) {
    for (int r = 0; r < rows; ++r) {
      const Eigen::Vector2d at = Eigen::Vector2d(c, r) * size * (1.0 - g.overlap) + Eigen::Vector2d(stage(random), stage(random));
      g.truth_px.push_back(at);
      g.layout.tiles.push_back({fmt::format("t{}.tif", g.images.size()), r, c, std::nullopt,
                                static_cast<int>(g.images.size() + 2), std::nullopt});
      const imaging::TileImage ideal = scene.Photograph(at - Eigen::Vector2d::Constant(margin), size + 2 * margin,
                                                        size + 2 * margin, random);
      g.images.push_back(field.Identity() ? ideal : imaging::DistortTile(ideal, margin, field));
    }
  }
  g.layout.rows = rows, g.layout.cols = cols;
  return g;
}

StitchResult Rigid(const DistortedGrid& g) {
  StitchOptions options;
  options.overlap = g.overlap;
  return StitchTiles(g.layout, g.images, options);
}

// The terms: no constant and no linear part (they are what the overlaps cannot tell), radial and tangential first.
TEST(FieldDistortion, TermsLeaveOutTheLinearPart) {
  EXPECT_EQ(imaging::FieldDistortionTermNames(2).size(), 6u);   // p1, p2 and 4 of the 6 quadratic monomials
  EXPECT_EQ(imaging::FieldDistortionTermNames(3).size(), 14u);  // + k1 and 7 of the 8 cubic ones
  EXPECT_EQ(imaging::FieldDistortionTermNames(3)[0], "p1");
  EXPECT_EQ(imaging::FieldDistortionTermNames(3)[6], "k1");
  EXPECT_THROW(imaging::FieldDistortionTermNames(1), std::invalid_argument);
  EXPECT_THROW(imaging::FieldDistortionTermNames(imaging::kMaxDistortionOrder + 1), std::invalid_argument);
  // k1 is the displacement at the middle of the left and right edges, along x, as scangen's --distortion-px.
  const imaging::FieldDistortion f = Field(512, {{"k1", 2.0}});
  EXPECT_NEAR(f.Displacement(Eigen::Vector2d(511.5, 255.5)).x(), 2.0, 1e-12);
  EXPECT_NEAR(f.Displacement(Eigen::Vector2d(255.5, 255.5)).norm(), 0.0, 1e-12);
}

// Undistorting a distorted tile gives the ideal image back (cubic resampling twice: under 1 % of the texture's
// contrast rms, 5 % at worst), and a round trip of a pixel through the field is exact.
// The terms stitching holds (imaging::kHeldStretchTerms): an odd power of one coordinate alone, and the radial
// terms that contain one; an overlap at the middle of two tiles a step s apart sees x^3 - (x - s)^3 stationary there.
TEST(FieldDistortion, StretchTermsAreTheOddPowersOfOneCoordinate) {
  const auto named = [](int order) {
    std::vector<std::string> out;
    for (int t : imaging::FieldDistortionStretchTerms(order)) out.push_back(imaging::FieldDistortionTermNames(order)[t]);
    return out;
  };
  EXPECT_TRUE(named(2).empty());
  EXPECT_EQ(named(3), (std::vector<std::string>{"k1", "dx_x3", "dx_y3", "dy_x3"}));
  EXPECT_EQ(named(4), named(3));
  EXPECT_EQ(named(5), (std::vector<std::string>{"k1", "dx_x3", "dx_y3", "dy_x3", "k2", "dx_x5", "dx_y5", "dy_x5"}));
}

TEST(FieldDistortion, UndistortInvertsDistort) {
  const imaging::FieldDistortion f = Field(128, {{"k1", 3.0}, {"p2", 0.5}, {"dy_x2", -1.0}});
  const Eigen::Vector2d u(17.3, 101.9);
  const Eigen::Vector2d raw = f.RawPixel(u);
  EXPECT_NEAR((raw + f.Displacement(raw) - u).norm(), 0.0, 1e-9);
  std::mt19937_64 random(3);
  artefacts::TileCameraOptions camera;
  camera.noise = 0.0, camera.vignetting = 0.0, camera.max_frequency = 0.1;
  const artefacts::TileScene scene(camera, random);
  const int margin = 16;
  const imaging::TileImage ideal = scene.Photograph(Eigen::Vector2d::Zero(), 128 + 2 * margin, 128 + 2 * margin, random);
  const imaging::TileImage back = imaging::UndistortTile(imaging::DistortTile(ideal, margin, f), f);
  double worst = 0.0, sum = 0.0;
  for (int y = 16; y < 112; ++y) {
    for (int x = 16; x < 112; ++x) {
      const double e = std::abs(double(back(y, x)) - ideal(y + margin, x + margin));
      worst = std::max(worst, e), sum += e * e;
    }
  }
  EXPECT_LT(std::sqrt(sum / (96.0 * 96.0)), 0.01 * camera.contrast);
  EXPECT_LT(worst, 0.05 * camera.contrast);
}

// A 3 x 3 grid (20 % overlap) through tangential and polynomial terms and the cross part of a radial one (k1 = 2.5
// px less its x^3 in dx and y^3 in dy, which stitching holds: imaging::kHeldStretchTerms): the field comes back
// within 0.1 px rms over the tile, the positions within 0.1 px of the truth where the rigid registration is 3 px
// off (0.0005 px and 0.006 px worst measured). The renderer integrates each pixel (DistortTile): the overlaps'
// quarters scatter little more than their points allow (block scatter 1.43; 2.1 when it took one point a pixel
// through OpenCV's cubic, whose phase-dependent shift every overlap of one direction shared; 1.00 before the second
// round's windows followed the field, when the points scattered 0.041 px, not 0.017, and the field missed by
// 0.0023 px). The standardised position errors read 0.44: the loops' misclosures widen u more than these pairs err.
TEST(StitchWithoutDistortion, RecoversAKnownFieldAndThePositions) {
  const imaging::FieldDistortion truth =
      Field(384, {{"dx_xy2", 2.5}, {"dy_x2y", 2.5}, {"p1", 0.4}, {"dx_x2", -0.6}, {"dy_xy2", 0.5}});
  const DistortedGrid g = RenderGrid(3, 3, 384, truth, 11);
  const StitchResult rigid = Rigid(g);
  ASSERT_EQ(rigid.accepted, 12);
  StitchDistortionOptions options;
  options.order = 3;
  const StitchDistortionResult r = StitchWithoutDistortion(rigid, g.images, options);
  EXPECT_LT(FieldDifferenceRms(r.fit.field, truth), 0.1);
  double rigid_worst = 0.0, worst = 0.0, z2 = 0.0;
  for (size_t i = 1; i < g.images.size(); ++i) {
    const Eigen::Vector2d t = g.truth_px[i] - g.truth_px[0];
    rigid_worst = std::max(rigid_worst, (rigid.registration.positions.positions_px[i] - t).norm());
    const Eigen::Vector2d e = r.fit.positions_px[i] - t;
    worst = std::max(worst, e.norm());
    z2 += e.cwiseQuotient(r.sigma_px[i]).squaredNorm();
  }
  EXPECT_LT(worst, 0.1);
  EXPECT_GT(rigid_worst, 10.0 * worst);
  EXPECT_LT(std::sqrt(z2 / (2.0 * (g.images.size() - 1))), 1.25);
  EXPECT_LT(r.fit.point_sigma_px, 0.025);        // 0.017 px: b's windows warped to a's view in the second round
  EXPECT_LT(r.fit.block_scatter_factor, 1.6);  // 1.43: the quarters of an overlap share little renderer's error
  EXPECT_GT(r.mean_overlap_ncc_after, r.mean_overlap_ncc_before);
  fmt::print("field error {:.4f} px rms (u {:.4f}); positions {:.3f} px worst (rigid {:.3f}); standardised rms {:.2f}; "
             "point sigma {:.3f} px, {} points; u widened by the pairs {:.2f}, the overlaps' quarters {:.2f}\n",
             FieldDifferenceRms(r.fit.field, truth), r.fit.field.DisplacementSigmaPx(), worst, rigid_worst,
             std::sqrt(z2 / (2.0 * (g.images.size() - 1))), r.fit.point_sigma_px, r.fit.points,
             r.fit.pair_scatter_factor, r.fit.block_scatter_factor);

  // The field saved and read back is the same field; stitching with it finds the same positions.
  const std::string file = testing::TempDir() + "/field.json";
  WriteFieldDistortion(file, r.fit.field);
  const imaging::FieldDistortion read = ReadFieldDistortion(file);
  EXPECT_LT(FieldDifferenceRms(read, r.fit.field), 1e-12);
  // The held terms are 0 with no uncertainty, and named.
  const std::vector<std::string>& names = imaging::FieldDistortionTermNames(3);
  ASSERT_EQ(r.fit.held_terms, imaging::FieldDistortionStretchTerms(3));
  for (int t : r.fit.held_terms) {
    EXPECT_EQ(r.fit.field.coefficients(t), 0.0) << names[static_cast<size_t>(t)];
    EXPECT_EQ(r.fit.field.covariance(t, t), 0.0) << names[static_cast<size_t>(t)];
  }
  options.known = read;
  const StitchDistortionResult again = StitchWithoutDistortion(rigid, g.images, options);
  EXPECT_FALSE(again.identified);
  for (size_t i = 0; i < g.images.size(); ++i) EXPECT_LT((again.fit.positions_px[i] - r.fit.positions_px[i]).norm(), 0.02);
}

// The grid without the tiles at `missing` (row, col): a layout with holes.
DistortedGrid WithHoles(const DistortedGrid& g, const std::vector<std::pair<int, int>>& missing) {
  DistortedGrid out;
  out.overlap = g.overlap;
  for (size_t i = 0; i < g.images.size(); ++i) {
    const imaging::TileLayoutEntry& tile = g.layout.tiles[i];
    if (std::find(missing.begin(), missing.end(), std::pair{tile.row, tile.col}) != missing.end()) continue;
    out.layout.tiles.push_back(tile), out.images.push_back(g.images[i]), out.truth_px.push_back(g.truth_px[i]);
  }
  out.layout.rows = g.layout.rows, out.layout.cols = g.layout.cols;
  return out;
}

// Holes in the layout: a 3 x 3 grid without two corners (7 tiles, 8 pairs, still both directions at every step) gives
// the field and the positions as the full grid does (0.1 px); without (0, 1) and (1, 0) the first tile has no
// neighbour beside it: the corner it shares with (1, 1) places it (0.1 px); and when that corner holds nothing (the
// first tile blank), the stage alone does: the others keep their places among themselves (0.1 px) and carry the
// stage's uncertainty against it, and the fit holds their group at its earliest tile.
TEST(StitchWithoutDistortion, LayoutsWithHoles) {
  const imaging::FieldDistortion truth = Field(384, {{"dx_xy2", 2.5}, {"dy_x2y", 2.5}, {"p1", 0.4}});
  const DistortedGrid full = RenderGrid(3, 3, 384, truth, 11);
  const DistortedGrid corners = WithHoles(full, {{0, 2}, {2, 0}});
  const StitchResult rigid = Rigid(corners);
  ASSERT_EQ(rigid.registration.pairs.size(), 8u);
  ASSERT_EQ(rigid.accepted, 8);
  EXPECT_TRUE(rigid.without_neighbour.empty());
  const StitchDistortionResult r = StitchWithoutDistortion(rigid, corners.images, {});
  EXPECT_LT(FieldDifferenceRms(r.fit.field, truth), 0.1);
  double z2 = 0.0;
  for (size_t i = 1; i < corners.images.size(); ++i) {
    const Eigen::Vector2d e = r.fit.positions_px[i] - (corners.truth_px[i] - corners.truth_px[0]);
    EXPECT_LT(e.norm(), 0.1) << i;
    z2 += e.cwiseQuotient(r.sigma_px[i]).squaredNorm();
  }
  EXPECT_LT(std::sqrt(z2 / (2.0 * (corners.images.size() - 1))), 1.25);

  DistortedGrid alone = WithHoles(full, {{0, 1}, {1, 0}});
  const StitchResult corner = Rigid(alone);
  ASSERT_EQ(corner.without_neighbour, std::vector<std::string>{"t0.tif (row 0 col 0)"});
  ASSERT_EQ(corner.registration.pairs.size(), 7u);  // 6 beside, 1 corner
  EXPECT_EQ(corner.accepted, 7);
  const StitchDistortionResult q = StitchWithoutDistortion(corner, alone.images, {});
  for (size_t i = 1; i < alone.images.size(); ++i) {
    EXPECT_LT((q.fit.positions_px[i] - (alone.truth_px[i] - alone.truth_px[0])).norm(), 0.1) << i;
  }
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (Eigen::Index k = 0; k < alone.images[0].size(); ++k) alone.images[0].data()[k] = 0.5f + noise(rng);
  const StitchResult apart = Rigid(alone);
  EXPECT_EQ(apart.at_stage_position.size(), 1u);  // the earliest of the others (the blank first one is the frame)
  const StitchDistortionResult s = StitchWithoutDistortion(apart, alone.images, {});
  EXPECT_LT(FieldDifferenceRms(s.fit.field, truth), 0.1);
  for (size_t i = 2; i < alone.images.size(); ++i) {
    const Eigen::Vector2d found = s.fit.positions_px[i] - s.fit.positions_px[1];
    EXPECT_LT((found - (alone.truth_px[i] - alone.truth_px[1])).norm(), 0.1) << i;
    // Against the first tile, the stage's uncertainty (the rigid solve's for the group's earliest tile), not the fit's.
    EXPECT_GE(s.sigma_px[i].minCoeff(), apart.registration.positions.sigma_px[1].minCoeff()) << i;
  }
  EXPECT_GT(s.sigma_px[1].minCoeff(), 0.3);
}

// The held-out confocal grids' shape on the project's own renderer, at their size: 4 x 4 tiles of 1024 px, 10 %,
// serpentine, a stage skew of 6 px per row along x and 0.7 px per column along y (a repeatability of 0.5 px on
// top), holes at corners, through the authors' field shape (23 px at the edge) or none. FVM_HELD_OUT_SWEEP=1 (a few
// minutes a row on 2 cores); rigid and with the field: positions after the common offset, standardised errors.
TEST(StitchWithoutDistortion, HeldOutShapeOnTheRenderer) {
  if (!std::getenv("FVM_HELD_OUT_SWEEP")) GTEST_SKIP() << "FVM_HELD_OUT_SWEEP=1 runs it";
  const int size = 1024;
  // The authors' field (identif_case1.json): 11.6 px of x y^2 in dx, -23.3 px of x^2 y in dy.
  const imaging::FieldDistortion authors = Field(size, {{"dx_xy2", 11.63}, {"dy_x2y", -23.34}});
  for (const bool with_field : {false, true}) {
    for (const std::vector<std::pair<int, int>>& missing :
         std::vector<std::vector<std::pair<int, int>>>{{}, {{0, 0}}, {{0, 0}, {3, 0}}, {{1, 0}, {2, 0}, {3, 0}}}) {
      const imaging::FieldDistortion field = with_field ? authors : imaging::FieldDistortion{};
      std::mt19937_64 random(21);
      artefacts::TileCameraOptions camera;
      camera.vignetting = 0.1;
      const artefacts::TileScene scene(camera, random);
      std::normal_distribution<double> stage(0.0, 0.5);
      DistortedGrid g;
      g.overlap = 0.1;
      const int margin = field.Identity() ? 0 : static_cast<int>(std::ceil(field.LargestDisplacementPx())) + 6;
      for (int r = 0; r < 4; ++r) {
        for (int k = 0; k < 4; ++k) {
          const int c = r % 2 == 1 ? 3 - k : k;
          const Eigen::Vector2d at = Eigen::Vector2d(c, r) * size * 0.9 + Eigen::Vector2d(6.0 * r, 0.7 * c) +
                                     Eigen::Vector2d(stage(random), stage(random));
          if (std::find(missing.begin(), missing.end(), std::pair{r, c}) != missing.end()) continue;
          g.truth_px.push_back(at);
          g.layout.tiles.push_back({fmt::format("r{}c{}.tif", r, c), r, c, std::nullopt,
                                    static_cast<int>(g.images.size() + 2), std::nullopt});
          const imaging::TileImage ideal = scene.Photograph(at - Eigen::Vector2d::Constant(margin), size + 2 * margin,
                                                            size + 2 * margin, random);
          g.images.push_back(field.Identity() ? ideal : imaging::DistortTile(ideal, margin, field));
        }
      }
      g.layout.rows = 4, g.layout.cols = 4;
      const StitchResult rigid = Rigid(g);
      const auto judge = [&](const std::vector<Eigen::Vector2d>& found, const std::vector<Eigen::Vector2d>& sigma) {
        const size_t n = found.size();
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (size_t i = 0; i < n; ++i) mean += (found[i] - found[0] - (g.truth_px[i] - g.truth_px[0])) / double(n);
        double sum = 0.0, z = 0.0;
        for (size_t i = 0; i < n; ++i) {
          const Eigen::Vector2d e = found[i] - found[0] - (g.truth_px[i] - g.truth_px[0]);
          sum += (e - mean).squaredNorm();
          if (i > 0) z += e.cwiseQuotient(sigma[i]).squaredNorm();
        }
        return std::pair{std::sqrt(sum / double(n)), std::sqrt(z / (2.0 * double(n - 1)))};
      };
      const auto [rigid_rms, rigid_z] = judge(rigid.registration.positions.positions_px, rigid.registration.positions.sigma_px);
      std::string line = fmt::format("{} ({:.1f} px) holes {} | pairs {}/{} | rigid {:.3f} px z {:.2f}", with_field ? "authors" : "none   ",
                                     field.Identity() ? 0.0 : field.LargestDisplacementPx(), missing.size(), rigid.accepted, rigid.registration.pairs.size(), rigid_rms, rigid_z);
      try {
        const StitchDistortionResult r = StitchWithoutDistortion(rigid, g.images, {});
        const auto [rms, z] = judge(r.fit.positions_px, r.sigma_px);
        line += fmt::format(" | field +{} pairs: {:.3f} px z {:.2f}, field {:.3f} px, ncc {:.3f} -> {:.3f}",
                            r.pairs_registered_undistorted, rms, z, FieldDifferenceRms(r.fit.field, field.Identity() ? Field(size, {}) : field),
                            r.mean_overlap_ncc_before, r.mean_overlap_ncc_after);
      } catch (const imaging::FieldDistortionUndeterminable& e) {
        line += fmt::format(" | field refused: {}", e.what());
      }
      fmt::print("{}\n", line);
    }
  }
}

// A strip of tiles in one row sees how the field changes along x only: terms in y alone are refused by name.
TEST(StitchWithoutDistortion, RefusesAStripInOneDirection) {
  const DistortedGrid g = RenderGrid(1, 2, 256, Field(256, {{"k1", 2.0}}), 5);
  const StitchResult rigid = Rigid(g);
  ASSERT_EQ(rigid.accepted, 1);
  try {
    StitchWithoutDistortion(rigid, g.images, {});
    FAIL() << "a 2-tile strip determined the field";
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    EXPECT_NE(std::string(e.what()).find("dx_y2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("both x and y"), std::string::npos) << e.what();
  }
}

// Overlaps without texture show no field: refused, not a field of zeros.
TEST(StitchWithoutDistortion, RefusesTextureFreeOverlaps) {
  const DistortedGrid g = RenderGrid(2, 2, 256, imaging::FieldDistortion{}, 5, false);
  StitchResult rigid = Rigid(g);
  // Nothing registers on a blank part; give the pairs their nominal offsets as if it had.
  for (imaging::PairRegistration& p : rigid.registration.pairs) p.accepted = true, p.offset_px = p.nominal_px;
  try {
    StitchWithoutDistortion(rigid, g.images, {});
    FAIL() << "texture-free overlaps determined a field";
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    EXPECT_NE(std::string(e.what()).find("texture"), std::string::npos) << e.what();
  }
}

// Order 6 over the thin overlaps of 2 x 2 tiles: more than they determine over the whole tile; refused, naming the
// order and the terms.
TEST(StitchWithoutDistortion, RefusesTooHighAnOrder) {
  const DistortedGrid g = RenderGrid(2, 2, 256, Field(256, {{"k1", 2.0}}), 7);
  const StitchResult rigid = Rigid(g);
  StitchDistortionOptions options;
  options.order = imaging::kMaxDistortionOrder;
  try {
    StitchWithoutDistortion(rigid, g.images, options);
    FAIL() << "order " << options.order << " was determined by 4 overlaps";
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    EXPECT_NE(std::string(e.what()).find("order"), std::string::npos) << e.what();
    fmt::print("{}\n", e.what());
  }
}

}  // namespace
}  // namespace fvm::workflows
