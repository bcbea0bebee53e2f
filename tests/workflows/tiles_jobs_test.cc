// The tiles jobs (workflows/tiles_plan.h, stitching_strategies.h, tiles_synthesize.h) as a script calls them: the
// published plan of the 6 x 6 grid, calibration scans and their layouts, the strategies under a calibrated stage,
// synthesized sets with their truth, and what each refuses by the option's name.

#include <fmt/core.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "stage/io/calibration_file.h"
#include "workflows/calibrate.h"
#include "workflows/stitching_strategies.h"
#include "workflows/tiles_plan.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::workflows {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::filesystem::path TilesJobsScratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("fvm_tiles_jobs_test_{}_{}", name, ::getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

std::string TilesJobsRefusal(const std::function<void()>& job) {
  try {
    job();
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

// [Pérez thesis] 5.7.2: the 6 x 6 grid at 10x and 13 % overlap takes 225 stitched tiles, 49 stitching-free; the
// region is the calottes' bounding box.
TEST(PlanTiles, ReproducesThePublishedGridPlan) {
  TilesPlanOptions options;
  options.artefact = "grid6x6";
  options.overlap = 0.13;
  const TilesPlan plan = PlanTiles(options);
  EXPECT_EQ(plan.stitched.tiles, 225);
  ASSERT_TRUE(plan.free.has_value());
  EXPECT_EQ(plan.free_cost->tiles, 49);
  const Summary summary = Summarize(plan);
  EXPECT_EQ(summary.json["lens"], "10x");
  EXPECT_EQ(summary.json["stitched"]["tiles"], 225);
  EXPECT_EQ(summary.json["stitching_free"]["features"].size(), 36u);
  EXPECT_THAT(summary.text, HasSubstr("\nstitched             225"));
  EXPECT_THAT(summary.text, HasSubstr("\nstitching-free        49"));
  EXPECT_THAT(StitchedLayoutText(plan), StartsWith("# fvm tiles plan: field 1.62 mm, overlap 13 %"));
  const std::string free = StitchingFreeLayoutText(plan);  // a comment, the header and 49 tiles
  EXPECT_EQ(std::count(free.begin(), free.end(), '\n'), 51);
}

TEST(PlanTiles, RefusesByTheOptionsName) {
  TilesPlanOptions both;
  both.artefact = "grid6x6";
  both.features = "centres.csv";
  EXPECT_EQ(TilesJobsRefusal([&] { PlanTiles(both); }), "give --features or --artefact, not both");
  EXPECT_THAT(TilesJobsRefusal([] { PlanTiles({}); }), StartsWith("give --region x0,y0,x1,y1 (mm)"));
  TilesPlanOptions lens;
  lens.lens = "15x";
  EXPECT_THAT(TilesJobsRefusal([&] { PlanTiles(lens); }), HasSubstr("lens '15x' is unknown"));
  TilesPlanOptions region;
  region.region = imaging::Region{0, 0, 10, 10};
  const TilesPlan plan = PlanTiles(region);
  EXPECT_FALSE(plan.free.has_value());
  EXPECT_EQ(TilesJobsRefusal([&] { StitchingFreeLayoutText(plan); }), "--free-layout needs --features or --artefact");
}

// The 5x lens at 25 % steps 2.115 mm: 1 + ceil(30 / 2.115) = 16 tiles along a 30 mm row; row, column, diagonal at
// two heights; each layout written where the summary says.
TEST(PlanTiles, CalibrationScansAndTheirLayouts) {
  TilesPlanOptions options;
  options.calibration_scan = true;
  options.lens = "5x";
  options.overlap = 0.25;
  options.length_mm = 30.0;
  options.heights_mm = {-50.0, -40.0};
  options.scan_dir = TilesJobsScratch("scans").string();
  const TilesPlan plan = PlanTiles(options);
  ASSERT_EQ(plan.paths.size(), 6u);
  EXPECT_EQ(plan.path_costs[0].tiles, 16);
  WriteScanLayouts(plan);
  const Summary summary = Summarize(plan);
  int tiles = 0;
  for (size_t k = 0; k < plan.paths.size(); ++k) {
    const std::string layout = summary.json["paths"][k]["layout"];
    EXPECT_EQ(layout, ScanLayoutPath(options, plan.paths[k].name));
    EXPECT_TRUE(std::filesystem::exists(layout)) << layout;
    tiles += summary.json["paths"][k]["tiles"].get<int>();
  }
  EXPECT_EQ(summary.json["total"]["tiles"], tiles);
  EXPECT_THAT(summary.text, StartsWith("calibration scans: field 2.82 mm, overlap 25 %"));
  EXPECT_THAT(summary.text, ::testing::Not(HasSubstr("give --scan-dir")));
  std::filesystem::remove_all(options.scan_dir);
}

// Under a calibrated stage ([Pérez 2019] Table 1): a, every tile registered, is exact; b, e and f leave the whole
// row to the encoders and err alike; c and d grow with the distance to the last tile the encoders place.
TEST(StitchingStrategies, FollowThePublishedOrderUnderACalibratedStage) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 4;
  const BatchCalibration c = CalibrateBatch(artefacts::SimulateFvmBatch(sim).batch, {});
  const std::filesystem::path dir = TilesJobsScratch("strategies");
  std::filesystem::create_directories(dir);
  WriteFileAtomically(dir / "cal.json", stage::CalibrationToJson(c.result).dump(2));
  StitchingStrategiesOptions options;
  options.calibration = (dir / "cal.json").string();
  options.tiles = (dir / "row").string();
  EXPECT_EQ(TilesJobsRefusal([&] { SimulateStitchingStrategies(options); }), "--tiles needs --render");
  options.tiles.clear();
  const StitchingStrategies s = SimulateStitchingStrategies(options);
  ASSERT_EQ(s.results.size(), 6u);
  const auto error = [&](size_t k) { return std::abs(s.results[k].distance_error_um); };
  EXPECT_LT(error(0), 1e-4);
  EXPECT_NEAR(error(4), error(1), 1e-4);
  EXPECT_NEAR(error(5), error(1), 1e-4);
  EXPECT_LT(error(2), error(3));
  EXPECT_LT(error(3), error(1));
  const Summary summary = Summarize(s);
  EXPECT_EQ(summary.json["calibration"], options.calibration);
  EXPECT_EQ(summary.json["cases"][1]["case"], "b");
  EXPECT_THAT(summary.text, HasSubstr("stage model 27 from " + options.calibration));
  std::filesystem::remove_all(dir);
}

// The sparse set: 5 x 5 tiles of 245 x 183 px at 6 %, its layout and truth; the refusals name --bits and --texture.
TEST(SynthesizeTileSet, WritesASparseSetWithItsTruthAndRefusesByName) {
  TilesSynthesizeOptions options;
  options.texture = "sparse";
  options.output = TilesJobsScratch("sparse").string();
  const SynthesizedTileSet set = SynthesizeTileSet(options);
  EXPECT_EQ(set.files.size(), 25u);
  for (const auto& f : set.files) EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(options.output) / f)) << f;
  std::ifstream truth(std::filesystem::path(options.output) / "truth.csv");
  int lines = 0;
  for (std::string line; std::getline(truth, line);) ++lines;
  EXPECT_EQ(lines, 26);
  const Summary summary = Summarize(set);
  EXPECT_EQ(summary.json["width_px"], 245);
  EXPECT_EQ(summary.json["height_px"], 183);
  EXPECT_EQ(summary.text, "25 sparse tiles of 245 x 183 px (overlap 6 %), layout.csv and truth.csv (true positions, "
                          "px) written to " + options.output + "\n");
  std::filesystem::remove_all(options.output);

  TilesSynthesizeOptions bits = options;
  bits.bits = 8;
  EXPECT_EQ(TilesJobsRefusal([&] { SynthesizeTileSet(bits); }), "--bits: sparse tiles are 16-bit counts");
  TilesSynthesizeOptions both = options;
  both.artefact = "grid6x6";
  EXPECT_EQ(TilesJobsRefusal([&] { SynthesizeTileSet(both); }), "--texture sparse and --artefact: give one of them");
  TilesSynthesizeOptions wood;
  wood.output = options.output;
  wood.texture = "wood";
  EXPECT_EQ(TilesJobsRefusal([&] { SynthesizeTileSet(wood); }), "--texture wood: give waves or sparse");
  EXPECT_FALSE(std::filesystem::exists(options.output));
}

}  // namespace
}  // namespace fvm::workflows
