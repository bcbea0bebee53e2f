#include "workflows/stitch.h"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include "artefacts/simulation/tile_synthesis.h"

namespace fvm::workflows {
namespace {

imaging::TileLayout LayoutOf(const artefacts::SynthesizedTiles& tiles) {
  imaging::TileLayout layout;
  for (size_t i = 0; i < tiles.tiles.size(); ++i) {
    layout.tiles.push_back({fmt::format("t{}.tif", i), tiles.tiles[i].row, tiles.tiles[i].col, std::nullopt,
                            static_cast<int>(i + 2), std::nullopt});
  }
  return layout;
}

// A 3 x 3 grid with 1.5 px of stage error per axis: every pair registers, every tile lands within 0.3 px of its
// true place against the first (registration noise on 256 px textured tiles is a few hundredths of a pixel; 0.3 px
// leaves room for the chained positions), and the overlaps correlate as one image does with itself (NCC > 0.9).
TEST(StitchTiles, RegistersASyntheticGridToItsTruth) {
  artefacts::TileSynthesisOptions synth;
  synth.seed = 4;
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(synth);
  StitchOptions options;
  options.overlap = synth.overlap;
  int calls = 0;
  const StitchResult s = StitchTiles(LayoutOf(tiles), tiles.images, options, [&](int, int) { ++calls; });
  EXPECT_FALSE(s.from_stage);
  EXPECT_EQ(CountGridPairs(s.grid), 12);
  EXPECT_EQ(calls, 12);
  EXPECT_EQ(s.accepted, 12);
  EXPECT_TRUE(s.at_stage_position.empty());
  ASSERT_EQ(s.registration.positions.positions_px.size(), 9u);
  for (size_t i = 0; i < 9; ++i) {
    const Eigen::Vector2d found = s.registration.positions.positions_px[i] - s.registration.positions.positions_px[0];
    const Eigen::Vector2d truth = tiles.truth_px[i] - tiles.truth_px[0];
    EXPECT_LT((found - truth).norm(), 0.3) << "tile " << i;
  }
  EXPECT_EQ(s.ncc_pairs, 12);
  EXPECT_GT(s.mean_overlap_ncc, 0.9);
}

// With stage positions and a pixel size, the nominal grid is the stage's (image y runs down = -Y), not the overlap's.
TEST(NominalGrid, FromTheStageWhenThePixelSizeConvertsIt) {
  imaging::TileLayout layout;
  layout.tiles.push_back({"a.tif", 0, 0, Eigen::Vector2d(10.0, 5.0), 2, std::nullopt});
  layout.tiles.push_back({"b.tif", 0, 1, Eigen::Vector2d(10.2, 4.99), 3, std::nullopt});
  StitchOptions options;
  options.overlap = 0.5;
  bool from_stage = false;
  EXPECT_EQ(NominalGrid(layout, 400, 300, options, &from_stage)[1].nominal_px, Eigen::Vector2d(200.0, 0.0));
  EXPECT_FALSE(from_stage);
  options.pixel_mm = 0.001;
  const std::vector<imaging::GridTile> grid = NominalGrid(layout, 400, 300, options, &from_stage);
  EXPECT_TRUE(from_stage);
  EXPECT_NEAR(grid[1].nominal_px.x(), 200.0, 1e-9);
  EXPECT_NEAR(grid[1].nominal_px.y(), 10.0, 1e-9);
}

}  // namespace
}  // namespace fvm::workflows
