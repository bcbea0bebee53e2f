// Fiji tile configurations (imaging/io/fiji_tile_configuration.h): read as layouts (rows and columns clustered with
// the pitch, the positions kept as nominal), written in the registered form, bad input refused by file and line;
// the real configurations of ../shared/realdata/tiles where present.

#include "imaging/io/fiji_tile_configuration.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

std::filesystem::path FijiScratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fvm_fiji_tile_configuration_test";
  std::filesystem::create_directories(dir);
  return dir / name;
}

std::filesystem::path WriteFiji(const std::string& name, const std::string& text) {
  const auto path = FijiScratch(name);
  std::ofstream(path) << text;
  return path;
}

// What reading `text` (as a file named `name`) into a layout refuses, "" when it does not.
std::string FijiErrorOf(const std::string& name, const std::string& text) {
  try {
    ReadTileLayout(WriteFiji(name, text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

constexpr const char* kHeader = "# Define the number of dimensions we are working on\ndim = 2\n\n# Define the image coordinates\n";

// A 2 x 3 grid scanned serpentine (the second row right to left), registered: jitter of a few px, a negative
// coordinate and Java's exponent form, as Fiji writes them. Read as a layout whatever the extension.
TEST(FijiTileConfiguration, ReadsASerpentineRegisteredGridAsALayout) {
  const std::string text = std::string(kHeader) +
                           "a.tif; ; (0.0, 0.0)\n"
                           "b.tif; ; (460.5, -1.25)\n"
                           "c.tif;;(921.75,-2.5E0)\n"
                           "  # a comment between tiles\n"
                           "f.tif; ; (923.0, 358.0)\n"
                           "e.tif; ; (462.1, 357.5)\n"
                           "d.tif; ; (-3.0E-1, 3.6e2)\n";
  const auto path = WriteFiji("serpentine.csv", text);  // the extension does not matter
  ASSERT_TRUE(IsFijiTileConfiguration(path));
  const TileLayout layout = ReadTileLayout(path);
  EXPECT_EQ(layout.source, path.string());
  EXPECT_EQ(layout.rows, 2);
  EXPECT_EQ(layout.cols, 3);
  const std::vector<std::tuple<std::string, int, int, int>> expected = {
      {"a.tif", 0, 0, 5}, {"b.tif", 0, 1, 6}, {"c.tif", 0, 2, 7}, {"f.tif", 1, 2, 9}, {"e.tif", 1, 1, 10}, {"d.tif", 1, 0, 11}};
  ASSERT_EQ(layout.tiles.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    const TileLayoutEntry& t = layout.tiles[i];
    EXPECT_EQ(std::tie(t.file, t.row, t.col, t.line), expected[i]);
    EXPECT_FALSE(t.stage_mm.has_value());
  }
  ASSERT_TRUE(layout.tiles[5].nominal_px.has_value());
  EXPECT_EQ(*layout.tiles[5].nominal_px, Eigen::Vector2d(-0.3, 360.0));
  EXPECT_EQ(*layout.tiles[2].nominal_px, Eigen::Vector2d(921.75, -2.5));
  EXPECT_NO_THROW(CheckLayoutForStitching(layout));
  // The pitch the gaps show (the median of the steps), and the same grid from a pitch given by the tile size.
  const FijiTileConfiguration config = ReadFijiTileConfiguration(path);
  EXPECT_EQ(PitchFromGaps(config), Eigen::Vector2d(460.5, 357.5));
  const TileLayout given = FijiTileLayout(config, Eigen::Vector2d(512 * 0.9, 400 * 0.9));
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(std::tie(given.tiles[i].row, given.tiles[i].col), std::tie(layout.tiles[i].row, layout.tiles[i].col));
  }
  // A byte-order mark before the first line (Windows editors) changes nothing.
  const auto marked = WriteFiji("marked.txt", "\xEF\xBB\xBF" + text);
  ASSERT_TRUE(IsFijiTileConfiguration(marked));
  EXPECT_EQ(ReadTileLayout(marked).tiles[5].col, 0);
  // A CSV layout is not taken for one.
  EXPECT_FALSE(IsFijiTileConfiguration(WriteFiji("plain.csv", "# dim = 2\nfile,row,col\na.tif,0,0\n")));
  EXPECT_FALSE(IsFijiTileConfiguration(FijiScratch("absent.txt")));
}

// A grid with missing tiles gives the layout with its holes (the layout's own check decides on them); a whole missing
// column keeps its index, counted by the pitches between its neighbours.
TEST(FijiTileConfiguration, MissingTilesLeaveHolesAtTheirNodes) {
  const std::string text = std::string(kHeader) +
                           "a.tif; ; (1000.0, 500.0)\n"
                           "b.tif; ; (1090.5, 500.0)\n"
                           "d.tif; ; (1271.0, 501.0)\n"
                           "e.tif; ; (1000.0, 590.0)\n"
                           "h.tif; ; (1270.0, 591.0)\n";
  const TileLayout layout = FijiTileLayout(ParseFijiTileConfiguration(text, "holes.txt"), Eigen::Vector2d(90.0, 90.0));
  EXPECT_EQ(layout.rows, 2);
  EXPECT_EQ(layout.cols, 4);
  std::vector<std::pair<int, int>> nodes;
  for (const TileLayoutEntry& t : layout.tiles) nodes.emplace_back(t.row, t.col);
  EXPECT_EQ(nodes, (std::vector<std::pair<int, int>>{{0, 0}, {0, 1}, {0, 3}, {1, 0}, {1, 3}}));
  // Tiles that lie two pitches apart everywhere: the overlap is wrong (or the tiles between them missing).
  try {
    FijiTileLayout(ParseFijiTileConfiguration("dim = 2\na.tif; ; (0, 0)\nb.tif; ; (921, 1)\nc.tif; ; (1842, 2)\n",
                                              "overlap.txt"),
                   Eigen::Vector2d(512.0, 512.0));
    ADD_FAILURE() << "tiles 921 px apart were laid out with a pitch of 512 px";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "overlap.txt: no two columns of the grid are neighbours: the nearest lie 2 pitches of 512.0 px "
                           "apart along x; check --overlap (the pitch is the tile size times 1 - overlap), or give the "
                           "tiles between them");
  }
}

// dim = 3 is read where every tile lies in one plane; tiles in several planes (image stacks) are refused.
TEST(FijiTileConfiguration, ThreeDimensionsOnlyInOnePlane) {
  const std::string planar = "dim = 3\na.tif; ; (0, 0, 5.0)\nb.tif; ; (90, 0, 5)\n";
  const TileLayout layout = FijiTileLayout(ParseFijiTileConfiguration(planar, "p.txt"));
  EXPECT_EQ(layout.cols, 2);
  EXPECT_EQ(FijiErrorOf("stacks.txt", "dim = 3\na.tif; ; (0, 0, 0)\nb.tif; ; (90, 0, 12.5)\n"),
            FijiScratch("stacks.txt").string() +
                ":3: tile b.tif is at z = 12.5 px, the first tile at z = 0: tiles in several planes are image stacks; "
                "fvm stitch places 2-D tiles in one plane");
  EXPECT_EQ(FijiErrorOf("two.txt", "dim = 3\na.tif; ; (0, 0)\n"),
            FijiScratch("two.txt").string() + ":2: tile a.tif has 2 coordinates under dim = 3; give (x, y, z)");
}

TEST(FijiTileConfiguration, BadInputIsRefusedByFileAndLine) {
  const auto error = [](const std::string& name, const std::string& text) {
    const std::string e = FijiErrorOf(name, text);
    const std::string prefix = FijiScratch(name).string();
    return e.starts_with(prefix) ? e.substr(prefix.size()) : "unnamed: " + e;
  };
  EXPECT_EQ(error("malformed.txt", "dim = 2\na.tif; ; (0.0, 0.0)\nb.tif, (1.0, 2.0)\n"),
            ":3: cannot read 'b.tif, (1.0, 2.0)' as a tile; write 'name; ; (x, y)'");
  EXPECT_EQ(error("paren.txt", "dim = 2\na.tif; ; 0.0, 0.0\n"),
            ":2: cannot read 'a.tif; ; 0.0, 0.0' as a tile; write 'name; ; (x, y)'");
  EXPECT_EQ(error("number.txt", "dim = 2\na.tif; ; (0.0, 0,5)\n"),
            ":2: tile a.tif has 3 coordinates under dim = 2; give (x, y)");
  EXPECT_EQ(error("nan.txt", "dim = 2\na.tif; ; (NaN, 0)\n"),
            ":2: tile a.tif: coordinate 'NaN' is not a position in pixels (a finite number within 1e9); check the line");
  EXPECT_EQ(error("text.txt", "dim = 2\na.tif; ; (1.0x, 0)\n"),
            ":2: tile a.tif: coordinate '1.0x' is not a position in pixels (a finite number within 1e9); check the line");
  EXPECT_EQ(error("dim4.txt", "# four\ndim = 4\na.tif; ; (0, 0, 0, 0)\n"),
            ":2: dim = 4: fvm stitch places 2-D tiles; give 'dim = 2' (or 3 with every z equal)");
  EXPECT_EQ(error("dimtext.txt", "dim = two\n"), ":1: cannot read 'dim = two' as the dimension; write 'dim = 2'");
  EXPECT_EQ(error("series.txt", "dim = 2\nscan.czi; 3; (0, 0)\n"),
            ":2: tile scan.czi is series 3 of a multi-series file; fvm reads one image a file: export each tile as "
            "an image");
  EXPECT_EQ(error("multi.txt", "dim = 2\nmultiseries = true\n"),
            ":2: a multi-series configuration: fvm reads one image a file; export each tile as an image");
  EXPECT_EQ(error("twice.txt", "dim = 2\na.tif; ; (0, 0)\na.tif; ; (90, 0)\n"),
            ":3: tile a.tif is given twice (first on line 2); give each tile once");
  EXPECT_EQ(error("node.txt", "dim = 2\na.tif; ; (0, 0)\nb.tif; ; (100, 0)\nc.tif; ; (5, 2)\n"),
            ":4: tile c.tif and tile a.tif (line 2) are both at row 0 col 0 of the grid (pitch 95.0 x 95.0 px): "
            "give each node one tile, or check the positions and --overlap");
  // Halfway between two columns: on no node of the grid of the pitch the tile size gives (the gaps alone would read
  // a pitch of 50 px from it).
  try {
    FijiTileLayout(ParseFijiTileConfiguration("dim = 2\na.tif; ; (0, 0)\nb.tif; ; (100, 0)\nc.tif; ; (200, 0)\n"
                                              "d.tif; ; (0, 100)\ne.tif; ; (150, 100)\nf.tif; ; (200, 100)\n",
                                              "between.txt"),
                   Eigen::Vector2d(100.0, 100.0));
    ADD_FAILURE() << "a tile between two columns was placed";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "between.txt:6: tile e.tif at x = 150 px is 50.0 px from the nearest column of the grid "
                           "(pitch 100.0 px): it lies on no node, within a third of a pitch; check its position and "
                           "--overlap");
  }
  // A pitch of a pixel and a tile a billion pixels away: more columns than a layout may span, refused before an
  // index overflows.
  try {
    FijiTileLayout(ParseFijiTileConfiguration("dim = 2\na.tif; ; (0, 0)\nb.tif; ; (1e9, 0)\n", "far.txt"),
                   Eigen::Vector2d(1.0, 1.0));
    ADD_FAILURE() << "a grid of a billion columns was laid out";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "far.txt:3: tile b.tif is 1000000000 pitches of 1.0 px from the first tile along x: more "
                           "columns than a layout may span (100000); check the positions and --overlap");
  }
  EXPECT_EQ(error("empty.txt", "# Define the number of dimensions we are working on\ndim = 2\n"),
            ": no tiles; a Fiji tile configuration lists one 'name; ; (x, y)' line a tile");
  // A tile line before the dimension (such a file is a CSV layout to ReadTileLayout, whose reader says what it
  // expects).
  try {
    ParseFijiTileConfiguration("a.tif; ; (0, 0)\ndim = 2\n", "nodim.txt");
    ADD_FAILURE() << "a tile before the dimension was read";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "nodim.txt:1: a tile before the 'dim = 2' line; a Fiji tile configuration gives its "
                           "dimension first");
  }
  EXPECT_THROW(ReadFijiTileConfiguration(FijiScratch("absent.txt")), InputError);
}

// The registered form, exactly as Fiji writes it; it reads back to the same positions (4 decimals) and grid.
TEST(FijiTileConfiguration, WritesTheRegisteredFormThatReadsBack) {
  const std::vector<std::string> files = {"tile 1.tif", "sub/tile2.tif", "tile3.tif"};
  const std::vector<Eigen::Vector2d> positions = {{0.0, 0.0}, {920.51234, -0.03829}, {-1.5, 924.42843}};
  const std::string text = FormatFijiTileConfiguration(files, positions);
  EXPECT_EQ(text,
            "# Define the number of dimensions we are working on\ndim = 2\n\n# Define the image coordinates\n"
            "tile 1.tif; ; (0.0000, 0.0000)\nsub/tile2.tif; ; (920.5123, -0.0383)\ntile3.tif; ; (-1.5000, 924.4284)\n");
  const FijiTileConfiguration back = ParseFijiTileConfiguration(text, "back.txt");
  ASSERT_EQ(back.tiles.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.tiles[i].file, files[i]);
    EXPECT_NEAR((back.tiles[i].position_px - positions[i]).cwiseAbs().maxCoeff(), 0.0, 5e-5);
  }
  const TileLayout layout = FijiTileLayout(back);
  EXPECT_EQ(std::tie(layout.tiles[2].row, layout.tiles[2].col), std::make_tuple(1, 0));
  EXPECT_THROW(FormatFijiTileConfiguration({"a;b.tif"}, {{0.0, 0.0}}), InputError);
  EXPECT_THROW(FormatFijiTileConfiguration({" a.tif"}, {{0.0, 0.0}}), InputError);
}

// A brief fuzz: a registered configuration with 1-4 bytes changed, cut or given extra digits reads to a well-formed
// layout (every tile inside its rows x cols, one a node) or fails with an InputError, never otherwise.
TEST(FijiTileConfiguration, DamagedConfigurationsReadOrFailWithAnInputError) {
  const std::string valid = std::string(kHeader) +
                            "a.tif; ; (0.0, 0.0)\nb.tif; ; (460.5, -1.25)\nc.tif; ; (921.75, -2.5E0)\n"
                            "f.tif; ; (923.0, 358.0)\ne.tif; ; (462.1, 357.5)\nd.tif; ; (-3.0E-1, 3.6e2)\n";
  std::mt19937 random(43);
  for (int round = 0; round < 2000; ++round) {
    std::string bytes = valid;
    const int kind = static_cast<int>(random() % 10);
    std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
    if (kind == 0) {
      bytes.resize(where(random));
    } else if (kind == 1) {
      bytes.insert(where(random), std::string(1 + random() % 9, static_cast<char>('0' + random() % 10)));
    } else {
      for (int i = 0, n = 1 + static_cast<int>(random() % 4); i < n; ++i) bytes[where(random)] = static_cast<char>(random() % 256);
    }
    for (const bool given : {false, true}) {
      try {
        const TileLayout layout = FijiTileLayout(ParseFijiTileConfiguration(bytes, "fuzz.txt"),
                                                 given ? std::optional<Eigen::Vector2d>(Eigen::Vector2d(460.8, 360.0))
                                                       : std::nullopt);
        std::set<std::pair<int, int>> nodes;
        for (const TileLayoutEntry& t : layout.tiles) {
          ASSERT_TRUE(t.row >= 0 && t.row < layout.rows && t.col >= 0 && t.col < layout.cols) << "round " << round;
          ASSERT_TRUE(nodes.insert({t.row, t.col}).second) << "round " << round;
        }
      } catch (const InputError&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << "round " << round << ": " << e.what();
      }
    }
  }
}

// The configurations that come with the real tiles: Fiji's input (serpentine), its registered output, the authors'
// translations (negative, no blanks) and the starrynight strip (integers). Skipped where ../shared is absent.
TEST(FijiTileConfiguration, ReadsTheRealConfigurations) {
  const std::filesystem::path tiles = std::filesystem::path(FVM_REALDATA_DIR) / "tiles";
  if (!std::filesystem::exists(tiles / "confocal-3x4" / "TileConfiguration.txt")) GTEST_SKIP() << "../shared absent";
  for (const char* name : {"TileConfiguration.txt", "TileConfiguration.registered.txt", "TileConfiguration_case1.txt"}) {
    const TileLayout layout = ReadTileLayout(tiles / "confocal-3x4" / name);
    EXPECT_EQ(layout.rows, 3) << name;
    EXPECT_EQ(layout.cols, 4) << name;
    ASSERT_EQ(layout.tiles.size(), 12u) << name;
    // Serpentine: A001-A004 the first row, A005 ... A008 the second right to left, A009-A012 the third.
    for (const TileLayoutEntry& t : layout.tiles) {
      const int k = std::stoi(t.file.substr(t.file.find("_A") + 2, 3)) - 1;
      const int row = k / 4, col = row == 1 ? 3 - k % 4 : k % 4;
      EXPECT_EQ(std::tie(t.row, t.col), std::tie(row, col)) << name << " " << t.file;
    }
    EXPECT_NO_THROW(CheckLayoutForStitching(layout)) << name;
  }
  for (const char* name : {"tile_config.txt", "tile_config.registered.txt"}) {
    const TileLayout layout = ReadTileLayout(tiles / "starrynight" / name);
    EXPECT_EQ(layout.rows, 1) << name;
    EXPECT_EQ(layout.cols, 10) << name;
    for (size_t i = 0; i < layout.tiles.size(); ++i) EXPECT_EQ(layout.tiles[i].col, static_cast<int>(i)) << name;
  }
}

}  // namespace
}  // namespace fvm::imaging
