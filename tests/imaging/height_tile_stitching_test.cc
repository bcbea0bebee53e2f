// Stitching what a focus-variation instrument exports: height-map tiles of the 6 x 6 calotte grid, with the face's
// roughness as the only texture between the calottes, invalid points (NaN) on the steep flanks, and measurement
// noise of its own in every tile. Registered and fused, the tiles must give the calottes where a single map of the
// whole artefact has them.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/height_tile_synthesis.h"
#include "imaging/calotte_detection.h"
#include "imaging/tile_mosaic.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging {
namespace {

TEST(HeightTileStitching, FusedTilesGiveTheCalottesOfTheWholeMap) {
  // 5 x 5 tiles of 256 px (20 % overlap) of 10 um pixels, 0.5 um of roughness, 0.1 um of noise per tile.
  artefacts::HeightTileOptions options;
  options.rows = options.cols = 5;
  options.seed = 3;
  const artefacts::SynthesizedHeightTiles set = artefacts::SynthesizeHeightTiles(artefacts::CalotteGrid6x6(), options);
  const RegistrationResult result = RegisterTileGrid(set.images, set.tiles, {});
  int accepted = 0;
  for (const auto& pair : result.pairs) accepted += pair.accepted;
  double sum = 0.0;
  for (size_t i = 0; i < set.tiles.size(); ++i) {
    sum += (result.positions.positions_px[i] - set.truth_px[i]).squaredNorm();
  }
  const double rms = std::sqrt(sum / static_cast<double>(set.tiles.size()));
  std::printf("%d of %zu pairs accepted, rms position error %.4f px\n", accepted, result.pairs.size(), rms);
  // Roughness of 0.5 um under 0.1 um of noise is texture enough everywhere on the face.
  EXPECT_EQ(accepted, static_cast<int>(result.pairs.size()));
  EXPECT_LT(rms, 0.05);

  // Fuse into one map in the artefact's frame: the first tile's centre is where it was cut from.
  const HeightMap& map = set.surface.map;
  const auto calottes = [&](const std::vector<Eigen::Vector2d>& positions) {
    return DetectCalottes(
        MosaicToHeightMap(FuseTiles(set.images, positions), 256, 256, map.dx_mm, set.nominal_centre_mm.front()));
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
