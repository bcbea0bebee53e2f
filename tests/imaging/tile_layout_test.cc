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
    CheckLayoutComplete(ReadTileLayout(path));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TileLayout, RoundTrip) {
  std::vector<TileLayoutEntry> tiles = {{"a.tif", 0, 0, Eigen::Vector2d(1.5, 2.25), 0},
                                        {"b.tif", 1, 0, Eigen::Vector2d(1.5, 1.0), 0}};
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
  EXPECT_NO_THROW(CheckLayoutComplete(layout));
}

TEST(TileLayout, BadInputNamesFileLineAndTile) {
  Write(Scratch("hole.csv"), "file,row,col\na,0,0\nb,0,1\nc,1,1\n");
  EXPECT_NE(ErrorOf(Scratch("hole.csv")).find("hole: no tile at row 1 col 0"), std::string::npos);
  Write(Scratch("twice.csv"), "file,row,col\na,0,0\nb,0,0\n");
  EXPECT_NE(ErrorOf(Scratch("twice.csv")).find("twice.csv:3: tile row 0 col 0 is given twice"), std::string::npos);
  Write(Scratch("header.csv"), "name,row,col\na,0,0\n");
  EXPECT_NE(ErrorOf(Scratch("header.csv")).find("no 'file' column"), std::string::npos);
  Write(Scratch("negative.csv"), "file,row,col\na,-1,0\n");
  EXPECT_NE(ErrorOf(Scratch("negative.csv")).find("negative.csv:2:"), std::string::npos);
  EXPECT_NE(ErrorOf(Scratch("absent.csv")).find("absent.csv"), std::string::npos);
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
