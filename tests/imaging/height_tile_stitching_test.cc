// Stitching what a focus-variation instrument exports: height-map tiles of the 6 x 6 calotte grid, with the face's
// roughness as the only texture between the calottes, invalid points (NaN) on the steep flanks, and measurement
// noise of its own in every tile. Registered and fused, the tiles must give the calottes where a single map of the
// whole artefact has them.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "artefacts/artefact.h"
#include "artefacts/calotte_surface.h"
#include "imaging/calotte_detection.h"
#include "imaging/tile_mosaic.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging {
namespace {

struct HeightTiles {
  artefacts::CalotteSurface surface;
  std::vector<TileImage> images;
  std::vector<GridTile> tiles;
  std::vector<Eigen::Vector2d> truth_px;  // top-left corners in the map's image frame (row 0 = highest y)
};

// A rows x cols grid of 256 px tiles at 205 px steps (20 % overlap) cut from one rendered map of the grid
// (10 um pixels, 0.5 um of frozen roughness), each off its grid position by a whole-pixel stage error, with
// 0.1 um of noise of its own.
HeightTiles CutTiles(int rows, int cols, std::uint64_t seed) {
  artefacts::CalotteSurfaceOptions options;
  options.dx_mm = options.dy_mm = 0.01;
  options.noise_sigma_mm = 0.0005;
  options.max_slope_deg = 50.0;             // the 10x lens loses the steeper flanks: NaN rings inside the rims
  options.missing_fraction = 0.002;   // and a few dropouts
  options.seed = seed;
  HeightTiles out;
  out.surface = artefacts::RenderCalotteSurface(artefacts::CalotteGrid6x6(), options);
  const HeightMap& map = out.surface.map;
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int size = 256, step = 205;
  for (int col = 0; col < cols; ++col) {
    for (int row = 0; row < rows; ++row) {
      const Eigen::Vector2d nominal(col * step, row * step);
      Eigen::Vector2d truth = nominal;
      if (!out.tiles.empty()) truth += Eigen::Vector2d(std::round(1.5 * normal(random)), std::round(1.5 * normal(random)));
      truth += Eigen::Vector2d(2, 2);  // room for a stage error at the map's edge
      TileImage image(size, size);
      for (int r = 0; r < size; ++r) {
        for (int c = 0; c < size; ++c) {
          const int ix = static_cast<int>(truth.x()) + c, iy = map.size_y - 1 - (static_cast<int>(truth.y()) + r);
          image(r, c) = map.at(ix, iy) + static_cast<float>(0.0001 * normal(random));
        }
      }
      out.images.push_back(image);
      out.tiles.push_back({row, col, nominal});
      out.truth_px.push_back(truth - Eigen::Vector2d(2, 2));  // tile 0 at 0, 0
    }
  }
  return out;
}

TEST(HeightTileStitching, FusedTilesGiveTheCalottesOfTheWholeMap) {
  const HeightTiles set = CutTiles(5, 5, 3);
  const RegistrationResult result = RegisterTileGrid(set.images, set.tiles, {});
  int accepted = 0;
  for (const auto& pair : result.pairs) accepted += pair.accepted;
  double sum = 0.0;
  for (size_t i = 0; i < set.tiles.size(); ++i) {
    sum += (result.positions.positions_px[i] - (set.truth_px[i] - set.truth_px[0])).squaredNorm();
  }
  const double rms = std::sqrt(sum / static_cast<double>(set.tiles.size()));
  std::printf("%d of %zu pairs accepted, rms position error %.4f px\n", accepted, result.pairs.size(), rms);
  // Roughness of 0.5 um under 0.1 um of noise is texture enough everywhere on the face.
  EXPECT_EQ(accepted, static_cast<int>(result.pairs.size()));
  EXPECT_LT(rms, 0.05);

  // Fuse into one map in the artefact's frame: the first tile's centre is where it was cut from.
  const HeightMap& map = set.surface.map;
  const Eigen::Vector2d first_centre(map.x0_mm + (2 + 127.5) * map.dx_mm,
                                     map.y0_mm + (map.size_y - 1 - (2 + 127.5)) * map.dy_mm);
  const auto calottes = [&](const std::vector<Eigen::Vector2d>& positions) {
    return DetectCalottes(MosaicToHeightMap(FuseTiles(set.images, positions), 256, 256, map.dx_mm, first_centre));
  };
  // The reference: the calottes fitted in the single map the tiles were cut from. Stitching places tiles in x and
  // y; the heights are each tile's own, with its own noise, so the centres' z differ by the fits' scatter (up to
  // 1 um here, the same for any placement) and only x and y are compared.
  const CalotteDetection whole = DetectCalottes(map);
  const auto worst_error_um = [&](const CalotteDetection& found, int& matched) {
    double worst = 0.0;
    matched = 0;
    for (const auto& c : found.calottes) {
      if (c.at_border) continue;
      for (const auto& w : whole.calottes) {
        if ((c.fit.centre_mm.head<2>() - w.fit.centre_mm.head<2>()).norm() < 0.1) {
          worst = std::max(worst, (c.fit.centre_mm - w.fit.centre_mm).head<2>().norm() * 1e3);
          ++matched;
        }
      }
    }
    return worst;
  };
  int matched = 0;
  const double registered = worst_error_um(calottes(result.positions.positions_px), matched);
  // 5 x 5 tiles at 2.05 mm steps hold the 3 x 3 calottes at 4 mm pitch nearest the origin, whole.
  EXPECT_GE(matched, 9);
  std::vector<Eigen::Vector2d> stage;
  for (const auto& t : set.tiles) stage.push_back(t.nominal_px);
  int matched_stage = 0;
  const double at_stage = worst_error_um(calottes(stage), matched_stage);
  std::printf("%d calottes, worst lateral centre difference to the whole map's %.3f um registered, %.3f um at the "
              "stage positions\n", matched, registered, at_stage);
  // Registration's 0.004 px is 0.04 um at 10 um pixels; each tile's own 0.1 um of noise, fused over overlaps,
  // moves a fit laterally by about 0.1 um more (measured: 0.15 um in all).
  EXPECT_LT(registered, 0.3);
  EXPECT_GT(at_stage, 5.0);  // the stage's 1.5 px per tile is 15 um
}

}  // namespace
}  // namespace fvm::imaging
