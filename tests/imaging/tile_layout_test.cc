// Tile layout files and tile images: round trips and bad input.

#include "imaging/io/tile_layout.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/input_error.h"
#include "imaging/io/tile_image.h"

namespace fvm::imaging {
namespace {

std::filesystem::path Scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fvm_tile_layout_test";
  std::filesystem::create_directories(dir);
  return dir / name;
}

void Write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

std::string ErrorOf(const std::filesystem::path& path) {
  try {
    CheckLayoutForStitching(ReadTileLayout(path));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TileLayout, RoundTrip) {
  std::vector<TileLayoutEntry> tiles = {{"a.tif", 0, 0, Eigen::Vector2d(1.5, 2.25), 0, std::nullopt},
                                        {"b.tif", 1, 0, Eigen::Vector2d(1.5, 1.0), 0, std::nullopt}};
  const auto path = Scratch("round.csv");
  Write(path, "# planned\n" + FormatTileLayout(tiles));
  const TileLayout layout = ReadTileLayout(path);
  ASSERT_EQ(layout.tiles.size(), 2u);
  EXPECT_EQ(layout.rows, 2);
  EXPECT_EQ(layout.cols, 1);
  EXPECT_EQ(layout.tiles[1].file, "b.tif");
  EXPECT_EQ(layout.tiles[1].line, 4);  // comment, header, first tile
  ASSERT_TRUE(layout.tiles[0].stage_mm.has_value());
  EXPECT_DOUBLE_EQ(layout.tiles[0].stage_mm->y(), 2.25);
  EXPECT_NO_THROW(CheckLayoutForStitching(layout));
}

TEST(TileLayout, BadInputNamesFileLineAndTile) {
  Write(Scratch("apart.csv"), "file,row,col\na,0,0\nb,1,1\nc,0,2\n");
  EXPECT_EQ(ErrorOf(Scratch("apart.csv")),
            Scratch("apart.csv").string() + ":2: no two tiles are neighbours (tile a at row 0 col 0 has none, nor has "
                                            "any other): stitching registers neighbouring tiles; check the row and col columns");
  Write(Scratch("twice.csv"), "file,row,col\na,0,0\nb,0,0\n");
  EXPECT_NE(ErrorOf(Scratch("twice.csv")).find("twice.csv:3: tile row 0 col 0 is given twice"), std::string::npos);
  Write(Scratch("header.csv"), "name,row,col\na,0,0\n");
  EXPECT_NE(ErrorOf(Scratch("header.csv")).find("header.csv:1: the header has no column 'file'"), std::string::npos);
  Write(Scratch("negative.csv"), "file,row,col\na,-1,0\n");
  EXPECT_NE(ErrorOf(Scratch("negative.csv")).find("negative.csv:2:"), std::string::npos);
  EXPECT_NE(ErrorOf(Scratch("absent.csv")).find("absent.csv"), std::string::npos);
}

// Issue 19: row + 1 and col + 1 overflowed int and the presence grid was written out of bounds. Indices are now
// bounded while reading, before anything is sized by them.
TEST(TileLayout, HugeIndicesAreRefusedNamingFileAndLine) {
  Write(Scratch("overflow.csv"), "file,row,col\na.tif,0,2147483647\n");
  EXPECT_EQ(ErrorOf(Scratch("overflow.csv")),
            Scratch("overflow.csv").string() +
                ":2: column 'col' (field 3): 2147483647 is out of range; give a whole number from 0 to 99999");
  Write(Scratch("overflow_row.csv"), "# c\nfile,row,col\na.tif,0,0\nb.tif,2147483647,0\n");
  EXPECT_EQ(ErrorOf(Scratch("overflow_row.csv")),
            Scratch("overflow_row.csv").string() +
                ":4: column 'row' (field 2): 2147483647 is out of range; give a whole number from 0 to 99999");
  // Each index within its bound, but the grid they span is 100000 x 100000 tiles: refused at the line that makes it.
  Write(Scratch("wide.csv"), "file,row,col\na.tif,0,99999\nb.tif,99999,0\n");
  EXPECT_EQ(ErrorOf(Scratch("wide.csv")),
            Scratch("wide.csv").string() +
                ":3: tile row 99999 col 0 makes the grid 100000 x 100000, more than the 1000000 tiles a layout may "
                "span; check the row and col columns");
  // The largest grid allowed is read; its two tiles far apart are reported, nothing overflows.
  Write(Scratch("largest.csv"), "file,row,col\na.tif,0,99999\nb.tif,9,0\n");
  EXPECT_EQ(ErrorOf(Scratch("largest.csv")),
            Scratch("largest.csv").string() +
                ":2: no two tiles are neighbours (tile a.tif at row 0 col 99999 has none, nor has any other): stitching "
                "registers neighbouring tiles; check the row and col columns");
  // A layout built in code is checked too before the grid is allocated.
  TileLayout built;
  built.source = "built";
  built.rows = 2147483647;
  built.cols = 2;
  EXPECT_THROW(CheckLayoutForStitching(built), InputError);
}

// A region that is not a rectangle (Fiji's and MIST's grids with missing tiles, a tile the export left out) is
// stitched with the neighbours each tile has; a tile with none is named, for the stage to place.
TEST(TileLayout, HolesAreAllowedAndTilesWithoutNeighbourNamed) {
  Write(Scratch("holes.csv"), "file,row,col\na,0,0\nb,0,2\nc,1,1\nd,1,2\ne,2,0\nf,2,1\n");
  const TileLayout layout = ReadTileLayout(Scratch("holes.csv"));
  EXPECT_EQ(layout.rows, 3);
  EXPECT_EQ(layout.cols, 3);
  EXPECT_NO_THROW(CheckLayoutForStitching(layout));
  EXPECT_EQ(TilesWithoutNeighbour(layout), std::vector<size_t>{0});  // a at (0, 0): (0, 1) and (1, 0) missing
  Write(Scratch("single.csv"), "file,row,col\na,3,4\n");
  EXPECT_EQ(ErrorOf(Scratch("single.csv")), "");  // one tile: nothing to register, nothing wrong
}

TEST(TileLayout, FileNamesWithCommasAndQuotesRoundTrip) {
  std::vector<TileLayoutEntry> tiles = {{"scan, day 1/a \"b\".tif", 0, 0, Eigen::Vector2d(-0.5, 1e-7), 0, std::nullopt},
                                        {"#2.tif", 0, 1, Eigen::Vector2d(1.25, 0), 0, std::nullopt}};
  const std::string text = FormatTileLayout(tiles);
  EXPECT_EQ(text, "file,row,col,x,y\n\"scan, day 1/a \"\"b\"\".tif\",0,0,-0.500000,0.000000\n\"#2.tif\",0,1,1.250000,"
                  "0.000000\n");
  Write(Scratch("names.csv"), text);
  const TileLayout layout = ReadTileLayout(Scratch("names.csv"));
  ASSERT_EQ(layout.tiles.size(), 2u);
  EXPECT_EQ(layout.tiles[0].file, tiles[0].file);
  EXPECT_EQ(layout.tiles[1].file, "#2.tif");
  EXPECT_EQ(layout.cols, 2);
}

TEST(TileImage, RoundTripsEightSixteenBitAndFloat) {
  TileImage image(4, 5);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 5; ++x) image(y, x) = static_cast<float>(10 * y + x);
  }
  for (const auto& [name, type] : {std::pair{"t8.png", TilePixelType::kUint8},
                                   std::pair{"t16.tif", TilePixelType::kUint16},
                                   std::pair{"tf.tif", TilePixelType::kFloat}}) {
    WriteTileImage(Scratch(name), image, type);
    const TileImage back = ReadTileImage(Scratch(name));
    ASSERT_EQ(back.rows(), 4);
    ASSERT_EQ(back.cols(), 5);
    // Integer counts come back exactly (native units), floats bit for bit.
    EXPECT_NEAR((back - image).cwiseAbs().maxCoeff(), 0.0, 1e-3) << name;
  }
  EXPECT_THROW(ReadTileImage(Scratch("none.png")), InputError);
}

}  // namespace
}  // namespace fvm::imaging
