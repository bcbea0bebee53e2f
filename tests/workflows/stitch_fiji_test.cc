// fvm stitch with Fiji's tile configuration (imaging/io/fiji_tile_configuration.h): the synthesized 3 x 3 set given as
// a serpentine TileConfiguration.txt stitches to the positions of its CSV layout, its positions written in Fiji's
// registered form are those of the positions CSV, and the tile it cannot size is refused by the configuration's line.

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <unistd.h>

#include "core/input_error.h"
#include "imaging/io/fiji_tile_configuration.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"
#include "tests/workflows/stitch_tile_set.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::workflows {
namespace {

// file -> (x, y) text of a positions CSV, as written.
std::map<std::string, std::pair<std::string, std::string>> CsvPositionTexts(const std::string& csv) {
  std::map<std::string, std::pair<std::string, std::string>> out;
  std::stringstream lines(csv);
  std::string line;
  std::getline(lines, line);  // header
  while (std::getline(lines, line)) {
    std::stringstream cells(line);
    std::string file, x, y;
    std::getline(cells, file, ',');
    std::getline(cells, x, ',');
    std::getline(cells, y, ',');
    out[file] = {x, y};
  }
  return out;
}

// The 3 x 3 set of stitch_layout_test.cc (8-bit, 256 px, 20 % overlap, 1.5 px of stage error). Its Fiji
// configuration lists the tiles serpentine (the middle row right to left), at the nominal grid positions of the
// CSV layout: the same grid, the same nominal positions, so the same registration.
TEST(StitchFiji, AConfigurationStitchesAsItsLayoutAndTheFijiPositionsAreTheCsvPositions) {
  const TilesSynthesizeOptions synth = EightBitSetOptions(StitchScratch("stitch_fiji_test", "set"));
  const SynthesizedTileSet set = SynthesizeTileSet(synth);
  const std::filesystem::path dir(synth.output);
  const LayoutTiles csv = ReadLayoutTiles(dir / "layout.csv", 0, 0.2);
  std::string fiji = "# Define the number of dimensions we are working on\ndim = 2\n\n# Define the image coordinates\n";
  const double pitch = 256 * (1.0 - 0.2);
  for (int row = 0; row < 3; ++row) {
    for (int k = 0; k < 3; ++k) {
      const int col = row == 1 ? 2 - k : k;
      for (const auto& tile : csv.layout.tiles) {
        if (tile.row == row && tile.col == col) fiji += fmt::format("{}; ; ({}, {})\n", tile.file, col * pitch, row * pitch);
      }
    }
  }
  std::ofstream(dir / "TileConfiguration.txt") << fiji;
  const LayoutTiles read = ReadLayoutTiles(dir / "TileConfiguration.txt", 0, 0.2);
  ASSERT_EQ(read.layout.tiles.size(), 9u);
  EXPECT_EQ(read.layout.rows, 3);
  EXPECT_EQ(read.layout.cols, 3);
  EXPECT_EQ(read.layout.tiles[3].col, 2);  // the middle row starts on the right
  EXPECT_EQ(read.layout.tiles[3].row, 1);

  const StitchedLayout from_csv = StitchLayout(csv.layout, csv.images, StitchLayoutOptions{});
  const StitchedLayout from_fiji = StitchLayout(read.layout, read.images, StitchLayoutOptions{});
  EXPECT_EQ(Summarize(from_fiji).json["nominal"], "stage");  // the configuration's positions
  const auto a = CsvPositionTexts(PositionsCsv(from_csv));
  const auto b = CsvPositionTexts(PositionsCsv(from_fiji));
  ASSERT_EQ(a.size(), 9u);
  for (const auto& [file, xy] : a) {
    ASSERT_TRUE(b.contains(file)) << file;
    EXPECT_NEAR(std::stod(b.at(file).first), std::stod(xy.first), 1e-3) << file;
    EXPECT_NEAR(std::stod(b.at(file).second), std::stod(xy.second), 1e-3) << file;
  }

  // The registered form: one line a tile in the layout's order, the positions CSV's x and y to the digit.
  EXPECT_TRUE(IsFijiPositionsPath("out/TileConfiguration.registered.TXT"));
  EXPECT_FALSE(IsFijiPositionsPath("positions.csv"));
  const std::string written = PositionsFiji(from_fiji);
  const imaging::FijiTileConfiguration back = imaging::ParseFijiTileConfiguration(written, "registered.txt");
  ASSERT_EQ(back.tiles.size(), 9u);
  std::stringstream lines(written);
  std::string line;
  for (int skip = 0; skip < 4; ++skip) std::getline(lines, line);
  for (size_t i = 0; i < back.tiles.size(); ++i) {
    EXPECT_EQ(back.tiles[i].file, from_fiji.files[i]);
    std::getline(lines, line);
    const auto& [x, y] = b.at(back.tiles[i].file);
    EXPECT_EQ(line, back.tiles[i].file + "; ; (" + x + ", " + y + ")");
  }
  // Read back as a layout, it is the same grid.
  std::ofstream(dir / "registered.txt") << written;
  const LayoutTiles again = ReadLayoutTiles(dir / "registered.txt", 0, 0.2);
  for (size_t i = 0; i < 9; ++i) {
    EXPECT_EQ(again.layout.tiles[i].row, read.layout.tiles[i].row);
    EXPECT_EQ(again.layout.tiles[i].col, read.layout.tiles[i].col);
  }

  // The first tile's image gives the pitch: missing, it is refused by the configuration's line and name.
  std::ofstream(dir / "missing.txt") << "dim = 2\n# none\nabsent.tif; ; (0, 0)\n" << set.files[1] << "; ; (204.8, 0)\n";
  try {
    ReadLayoutTiles(dir / "missing.txt", 0, 0.2);
    ADD_FAILURE() << "a configuration whose first tile is missing was read";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "missing.txt").string() + ":3: tile absent.tif: ", 0), 0u) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fvm::workflows
