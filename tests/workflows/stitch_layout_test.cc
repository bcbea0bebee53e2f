// fvm stitch as a job (workflows/stitch_layout.h, stitch_summary.h): a synthesized tile set read as the command
// reads it, stitched back to its truth, its positions CSV and summary; the options and mosaics refused by name.

#include <fmt/core.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include <unistd.h>

#include "core/input_error.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"
#include "tests/workflows/stitch_tile_set.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::workflows {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::vector<std::vector<std::string>> CsvRows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> cells;
    std::stringstream cell(line);
    for (std::string c; std::getline(cell, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The set tests/fvm/tiles_cli_test.cmake stitches: 3 x 3 8-bit tiles, 1.5 px of stage error. Every pair
// registers; every tile lands within 0.15 px of its truth (the set's rms is 0.04 px, 8-bit quantisation); the CSV
// carries mm with the pixel size; the summary counts what the result holds and prints it.
TEST(StitchLayout, StitchesASynthesizedSetBackToItsTruthAndSummarizesIt) {
  const TilesSynthesizeOptions synth = EightBitSetOptions(StitchScratch("stitch_layout_test", "set"));
  const SynthesizedTileSet set = SynthesizeTileSet(synth);
  const LayoutTiles tiles = ReadLayoutTiles(std::filesystem::path(synth.output) / "layout.csv");
  EXPECT_EQ(tiles.pixel_type, imaging::TilePixelType::kUint8);
  StitchLayoutOptions options;
  options.stitch.pixel_mm = 0.001;
  EXPECT_EQ(StitchPairCount(tiles.layout, tiles.images, options.stitch), 12);
  const StitchedLayout stitched = StitchLayout(tiles.layout, tiles.images, options);
  EXPECT_EQ(stitched.files, set.files);

  const auto rows = CsvRows(PositionsCsv(stitched));
  const auto truth = CsvRows(ReadText(std::filesystem::path(synth.output) / "truth.csv"));
  ASSERT_EQ(rows.size(), 10u);
  EXPECT_EQ(fmt::format("{}", fmt::join(rows[0], ",")), "file,x,y,x_mm,y_mm,registered,u_x,u_y");
  for (size_t i = 1; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i][0], truth[i][0]);
    EXPECT_NEAR(std::stod(rows[i][1]), std::stod(truth[i][1]), 0.15) << rows[i][0];
    EXPECT_NEAR(std::stod(rows[i][2]), std::stod(truth[i][2]), 0.15) << rows[i][0];
    // mm: the first tile's centre is the origin without stage positions; +Y up, so y_mm = -y px x pixel.
    EXPECT_NEAR(std::stod(rows[i][3]), std::stod(rows[i][1]) * 0.001, 1e-6);
    EXPECT_NEAR(std::stod(rows[i][4]), -std::stod(rows[i][2]) * 0.001, 1e-6);
    EXPECT_EQ(rows[i][5], "1");
  }

  const Summary summary = Summarize(stitched);
  EXPECT_EQ(summary.json["tiles"], 9);
  EXPECT_EQ(summary.json["nominal"], "grid");
  EXPECT_EQ(summary.json["pairs_accepted"], 12);
  EXPECT_EQ(summary.json["pairs"].size(), 12u);
  EXPECT_EQ(summary.json["pairs"][0]["a"], set.files[0]);
  EXPECT_FALSE(summary.json.contains("distortion"));
  EXPECT_EQ(summary.json.begin().key(), "tiles");  // the keys in the order the command has always printed them
  EXPECT_THAT(summary.text, StartsWith("9 tiles of 256 x 256 px, 12 pairs, 12 accepted (quality >= 0.5); nominal "
                                       "positions from the grid and overlap\n  stage model from 6 east and 6 south"));
  EXPECT_THAT(summary.text, HasSubstr("\nlargest standard uncertainty of a registered tile against the first of its "
                                      "chain: "));
  // The report's data (tests/report/stitch_report_test.cc checks the page): one tile and one pair each.
  ASSERT_TRUE(summary.report.has_value());
  const auto& report = std::get<report::StitchReportData>(*summary.report);
  EXPECT_EQ(report.tiles.size(), 9u);
  EXPECT_EQ(report.pairs.size(), 12u);
  EXPECT_TRUE(report.field.empty());
  std::filesystem::remove_all(synth.output);
}

// The same set with a hole: its last tile (row 2, col 2) left out of layout.csv, as a layout read from another
// tool's export leaves a tile it could not place. The command reads it, every other tile is registered to its truth,
// the positions CSV has the eight, the summary names no tile without neighbour, and the mosaic is empty (NaN) where
// the hole is and filled elsewhere.
TEST(StitchLayout, StitchesALayoutWithAHoleAndFusesItsMosaic) {
  const TilesSynthesizeOptions synth = EightBitSetOptions(StitchScratch("stitch_layout_test", "hole"));
  const SynthesizedTileSet set = SynthesizeTileSet(synth);
  const std::filesystem::path layout = std::filesystem::path(synth.output) / "layout.csv";
  std::string text = ReadText(layout), kept;
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(",2,2") == std::string::npos) kept += line + "\n";
  }
  ASSERT_LT(kept.size(), text.size());
  std::ofstream(layout) << kept;
  const LayoutTiles tiles = ReadLayoutTiles(layout);
  ASSERT_EQ(tiles.images.size(), 8u);
  const StitchedLayout stitched = StitchLayout(tiles.layout, tiles.images, StitchLayoutOptions{});
  EXPECT_EQ(stitched.rigid.accepted, 10);
  const auto rows = CsvRows(PositionsCsv(stitched));
  const auto truth = CsvRows(ReadText(std::filesystem::path(synth.output) / "truth.csv"));
  ASSERT_EQ(rows.size(), 9u);
  for (size_t i = 1; i < rows.size(); ++i) {
    const auto t = std::find_if(truth.begin(), truth.end(), [&](const auto& r) { return r[0] == rows[i][0]; });
    ASSERT_NE(t, truth.end()) << rows[i][0];
    EXPECT_NEAR(std::stod(rows[i][1]), std::stod((*t)[1]), 0.15) << rows[i][0];
    EXPECT_NEAR(std::stod(rows[i][2]), std::stod((*t)[2]), 0.15) << rows[i][0];
    EXPECT_EQ(rows[i][3], "1") << rows[i][0];
  }
  const Summary summary = Summarize(stitched);
  EXPECT_EQ(summary.json["without_neighbour"], nlohmann::json::array());
  const imaging::Mosaic mosaic = FuseStitched(stitched, tiles.images);
  const imaging::TileImage& m = mosaic.image;
  EXPECT_TRUE(std::isnan(m(m.rows() - 5, m.cols() - 5)));  // the hole's corner
  EXPECT_TRUE(std::isfinite(m(5, 5)) && std::isfinite(m(m.rows() - 5, 5)) && std::isfinite(m(5, m.cols() - 5)));
  std::filesystem::remove_all(synth.output);
}

// Issue 42: the centre tile of the same set blank (the flat background of a sparse scene under camera noise): its
// four pairs of twelve place nothing, a third, and the run says so (the warning the command prints on stderr, and
// --json's unresolved_warning); the tile says registered 0 and carries the stage's spread, which covers where it is.
TEST(StitchLayout, SaysARunWithAQuarterOfItsPairsUnresolvedAndATileNoPairPlaces) {
  const TilesSynthesizeOptions synth = EightBitSetOptions(StitchScratch("stitch_layout_test", "blank"));
  const SynthesizedTileSet set = SynthesizeTileSet(synth);
  LayoutTiles tiles = ReadLayoutTiles(std::filesystem::path(synth.output) / "layout.csv");
  imaging::TileImage& blank = tiles.images[4];
  const float level = blank.mean();
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  for (Eigen::Index k = 0; k < blank.size(); ++k) blank.data()[k] = level + noise(rng);
  const StitchedLayout stitched = StitchLayout(tiles.layout, tiles.images, StitchLayoutOptions{});
  EXPECT_EQ(stitched.rigid.unresolved, 4);
  EXPECT_TRUE(stitched.rigid.mostly_unresolved);
  const Summary summary = Summarize(stitched);
  EXPECT_EQ(summary.json["pairs_unresolved"], 4);
  ASSERT_TRUE(summary.json["unresolved_warning"].is_string());
  EXPECT_THAT(summary.json["unresolved_warning"].get<std::string>(), StartsWith("4 of 12 pairs are unresolved"));
  EXPECT_EQ(summary.json["stage_fallback"], nlohmann::json::array({set.files[4]}));

  const auto rows = CsvRows(PositionsCsv(stitched));
  const auto truth = CsvRows(ReadText(std::filesystem::path(synth.output) / "truth.csv"));
  ASSERT_EQ(rows.size(), 10u);
  EXPECT_EQ(fmt::format("{}", fmt::join(rows[0], ",")), "file,x,y,registered,u_x,u_y");
  for (size_t i = 1; i < rows.size(); ++i) EXPECT_EQ(rows[i][3], i == 5 ? "0" : "1") << rows[i][0];
  // The blank tile: where the stage and its neighbours' rows and columns put it, within 4 of its u per axis, and
  // its u the stage's (1.5 px per axis in this set), not a registration's hundredths.
  for (const int k : {1, 2}) {
    const double error = std::stod(rows[5][static_cast<size_t>(k)]) - std::stod(truth[5][static_cast<size_t>(k)]);
    const double u = std::stod(rows[5][static_cast<size_t>(k + 3)]);
    EXPECT_GT(u, 0.5);
    EXPECT_LT(std::abs(error), 4.0 * u) << "axis " << k;
  }
  std::filesystem::remove_all(synth.output);
}

// A strip in one direction cannot tell the field's terms apart: refused naming --distortion and the layout.
TEST(StitchLayout, RefusesAFieldTheOverlapsCannotDetermineNamingTheLayout) {
  TilesSynthesizeOptions synth;
  synth.output = StitchScratch("stitch_layout_test", "strip").string();
  synth.rows = 1;
  synth.cols = 3;
  synth.tile_px = 128;
  (void)SynthesizeTileSet(synth);
  const LayoutTiles read = ReadLayoutTiles(std::filesystem::path(synth.output) / "layout.csv");
  StitchLayoutOptions options;
  options.distortion = StitchDistortionOptions{};
  try {
    StitchLayout(read.layout, read.images, options);
    FAIL() << "a strip identified a field";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith("--distortion, " + read.layout.source + ": "));
  }
  std::filesystem::remove_all(synth.output);
}

TEST(StitchOptions, CheckNamesTheOptionAsTheCommandSpellsIt) {
  const auto refusal = [](const std::function<void(StitchOptions&)>& change) {
    StitchOptions o;
    change(o);
    try {
      o.Check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal([](StitchOptions&) {}), "accepted");
  EXPECT_THAT(refusal([](StitchOptions& o) { o.overlap = 1.0; }), StartsWith("--overlap 1:"));
  EXPECT_THAT(refusal([](StitchOptions& o) { o.pixel_mm = -1.0; }), StartsWith("--pixel-mm -1:"));
  EXPECT_THAT(refusal([](StitchOptions& o) { o.registration.min_quality = 1.5; }), StartsWith("--min-quality:"));
  EXPECT_THAT(refusal([](StitchOptions& o) { o.registration.stage_sigma_px = 0.0; }), StartsWith("--stage-sigma-px:"));
  EXPECT_THAT(refusal([](StitchOptions& o) { o.threads = -2; }), StartsWith("--threads -2:"));
}

TEST(StitchMosaic, AHeightMapNeedsThePixelSizeAndFloatTiles) {
  EXPECT_NO_THROW(CheckMosaicPath("", 0.0));
  EXPECT_NO_THROW(CheckMosaicPath("m.tif", 0.0));
  EXPECT_NO_THROW(CheckMosaicPath("m.x3p", 0.01));
  EXPECT_THROW(CheckMosaicPath("m.x3p", 0.0), InputError);
  EXPECT_NO_THROW(CheckMosaicTiles("m.x3p", imaging::TilePixelType::kFloat));
  EXPECT_NO_THROW(CheckMosaicTiles("m.png", imaging::TilePixelType::kUint16));
  try {
    CheckMosaicTiles("m.x3p", imaging::TilePixelType::kUint16);
    FAIL() << "16-bit tiles made a height map";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith("--mosaic m.x3p: the tiles hold 16-bit counts, not heights"));
  }
}

}  // namespace
}  // namespace fvm::workflows
