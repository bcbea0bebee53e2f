#include "workflows/stitch.h"

#include <algorithm>
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

// Part of a synthesized grid, as a layout with holes: the tiles appended node by node, in the order of the appends.
struct GridPart {
  imaging::TileLayout layout;
  std::vector<imaging::TileImage> images;
  std::vector<Eigen::Vector2d> truth;

  explicit GridPart(const artefacts::SynthesizedTiles& tiles) : tiles_(tiles), full_(LayoutOf(tiles)) {
    for (const imaging::TileLayoutEntry& tile : full_.tiles) {  // the full grid's extent, holes or not
      layout.rows = std::max(layout.rows, tile.row + 1), layout.cols = std::max(layout.cols, tile.col + 1);
    }
  }
  void Append(int row, int col) {
    for (size_t i = 0; i < full_.tiles.size(); ++i) {
      if (full_.tiles[i].row != row || full_.tiles[i].col != col) continue;
      layout.tiles.push_back(full_.tiles[i]), images.push_back(tiles_.images[i]), truth.push_back(tiles_.truth_px[i]);
    }
  }

 private:
  const artefacts::SynthesizedTiles& tiles_;
  imaging::TileLayout full_;
};

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

// Holes in the layout (a region that is not a rectangle, tiles left out): a 3 x 4 grid without two corners and an
// inner tile, serpentine, first tile missing too: every present tile lands within 0.3 px of its truth against the
// layout's first, registered by the neighbours it has; nothing is named as without neighbour.
TEST(StitchTiles, RegistersAGridWithHoles) {
  artefacts::TileSynthesisOptions synth;
  synth.rows = 3, synth.cols = 4, synth.seed = 5;
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(synth);
  GridPart part(tiles);
  // Serpentine: row 0 left to right, row 1 right to left, row 2 left to right; without (0, 0), (2, 3) and (1, 2).
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) {
      const int c = r % 2 == 0 ? k : 3 - k;
      if (!((r == 0 && c == 0) || (r == 2 && c == 3) || (r == 1 && c == 2))) part.Append(r, c);
    }
  }
  const imaging::TileLayout& layout = part.layout;
  const std::vector<imaging::TileImage>& images = part.images;
  const std::vector<Eigen::Vector2d>& truth = part.truth;
  StitchOptions options;
  options.overlap = synth.overlap;
  const StitchResult s = StitchTiles(layout, images, options);
  EXPECT_EQ(CountGridPairs(s.grid), 9);  // 17 of the full grid less 2, 2 and 4 beside the holes
  EXPECT_EQ(s.accepted, 9);
  EXPECT_TRUE(s.at_stage_position.empty());
  EXPECT_TRUE(s.without_neighbour.empty());
  for (size_t i = 1; i < images.size(); ++i) {
    const Eigen::Vector2d found = s.registration.positions.positions_px[i] - s.registration.positions.positions_px[0];
    EXPECT_LT((found - (truth[i] - truth[0])).norm(), 0.3) << layout.tiles[i].row << " " << layout.tiles[i].col;
    EXPECT_TRUE(s.registration.positions.registered[i]);
  }
}

// Without (0, 1) and (1, 0) the first tile has no neighbour beside it: named, and registered through the corner it
// shares with (1, 1) (0.3 px). Its corner blank, the stage places it: the others keep their places among themselves
// (0.3 px) and carry against it the stage's uncertainty, the mean steps' included (the pairs' median steps held exact
// gave 0.8 px where the tile lay 2.8 px off, on cut grids of the held-out shape).
TEST(StitchTiles, NamesATileWithoutNeighbourAndPlacesItByItsCornerOrTheStage) {
  artefacts::TileSynthesisOptions synth;
  synth.rows = 3, synth.cols = 4, synth.seed = 5;
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(synth);
  GridPart part(tiles);
  for (const imaging::TileLayoutEntry& tile : LayoutOf(tiles).tiles) {  // the synthesized order, without two nodes
    if (!((tile.row == 0 && tile.col == 1) || (tile.row == 1 && tile.col == 0))) part.Append(tile.row, tile.col);
  }
  const imaging::TileLayout& layout = part.layout;
  std::vector<imaging::TileImage>& images = part.images;
  const std::vector<Eigen::Vector2d>& truth = part.truth;
  StitchOptions options;
  options.overlap = synth.overlap;
  const StitchResult by_corner = StitchTiles(layout, images, options);
  ASSERT_EQ(by_corner.without_neighbour, std::vector<std::string>{"t0.tif (row 0 col 0)"});
  EXPECT_EQ(CountGridPairs(by_corner.grid), 12);  // 17 of the full grid less 3 and 3 beside the holes, 1 corner
  EXPECT_EQ(by_corner.accepted, 12);
  EXPECT_TRUE(by_corner.at_stage_position.empty());
  for (size_t i = 1; i < images.size(); ++i) {
    const imaging::TilePositions& c = by_corner.registration.positions;
    EXPECT_LT(((c.positions_px[i] - c.positions_px[0]) - (truth[i] - truth[0])).norm(), 0.3) << i;
  }
  images[0].setConstant(images[0].mean());
  const StitchResult s = StitchTiles(layout, images, options);
  // The blank first tile is the frame; the earliest of the others (t2: the scan runs down columns) starts their chain
  // at its stage position.
  EXPECT_EQ(s.at_stage_position, std::vector<std::string>{"t2.tif"});
  const imaging::TilePositions& p = s.registration.positions;
  for (size_t i = 2; i < images.size(); ++i) {
    EXPECT_LT(((p.positions_px[i] - p.positions_px[1]) - (truth[i] - truth[1])).norm(), 0.3) << i;
    // Against the first tile: the stage's error (1.5 px per axis drawn), said by u.
    EXPECT_GT(p.sigma_px[i].minCoeff(), 0.5) << i;
    EXPECT_LT((p.positions_px[i] - p.positions_px[0] - (truth[i] - truth[0])).cwiseQuotient(p.sigma_px[i]).maxCoeff(), 3.0);
  }
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
