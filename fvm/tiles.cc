// fvm tiles plan: tile layouts with and without stitching (workflows/tiles_plan.h); `synthesize` and `simulate` in
// fvm/tiles_synthesize.cc and fvm/tiles_simulate.cc.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "core/file_io.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "imaging/tile_plan.h"
#include "workflows/tiles_plan.h"

namespace fvm::cli {
namespace {

struct PlanArgs {
  workflows::TilesPlanOptions job;
  // WxH and lists, parsed into `job` by ParseCompound.
  std::string tile_pixels = "1024x1024";
  std::string travel = "200x200";
  std::string heights = "-50";
  std::string output;
  std::string free_output;
  bool json = false;
};

// "WxH" as the two numbers ParseNumbers reads ("" when there is no x: refused there, naming the option).
std::string SplitAtX(const std::string& text) {
  const size_t x = text.find('x');
  return x == std::string::npos ? "" : text.substr(0, x) + "," + text.substr(x + 1);
}

// The options written as WxH or lists, into the job's numbers; InputError naming the option.
void ParseCompound(PlanArgs& args) {
  const auto wh = ParseNumbers(SplitAtX(args.tile_pixels), 2, "--tile-px " + args.tile_pixels, "1024x1024");
  args.job.tile_width_px = static_cast<int>(wh[0]);
  args.job.tile_height_px = static_cast<int>(wh[1]);
  if (!args.job.calibration_scan) return;
  const auto travel = ParseNumbers(SplitAtX(args.travel), 2, "--travel " + args.travel,
                                   "200x200 (mm; stage coordinates -W..0, -H..0)");
  args.job.travel_width_mm = travel[0];
  args.job.travel_height_mm = travel[1];
  args.job.heights_mm = ParseNumberList(args.heights, "--heights", "-50,-40");
}

void RunPlan(PlanArgs& args) {
  ParseCompound(args);
  const workflows::TilesPlan plan = workflows::PlanTiles(args.job);
  if (args.job.calibration_scan) {
    workflows::WriteScanLayouts(plan);
  } else {
    const std::string free = args.free_output.empty() ? "" : workflows::StitchingFreeLayoutText(plan);
    if (!args.output.empty()) WriteFileAtomically(args.output, workflows::StitchedLayoutText(plan));
    if (!args.free_output.empty()) WriteFileAtomically(args.free_output, free);
  }
  const workflows::Summary summary = workflows::Summarize(plan);
  if (args.json) {
    fmt::print("{}\n", summary.json.dump(2));
  } else {
    fmt::print("{}", summary.text);
  }
}

}  // namespace

void RegisterTiles(CLI::App& app) {
  CLI::App* tiles = app.add_subcommand("tiles", "plan tile layouts with and without stitching");
  tiles->require_subcommand(1);
  tiles->footer("Example:\n  fvm tiles plan --lens 10x --artefact grid6x6 --overlap 13");

  auto plan_args = std::make_shared<PlanArgs>();
  CLI::App* plan = tiles->add_subcommand("plan", "the stitched tile grid of a region and the stitching-free tiles "
                                                 "that cover given features, with scan time and data volume");
  plan->add_option("--lens", plan_args->job.lens, "lens: 2.5x (5.63 mm field), 5x (2.82), 10x (1.62), 20x (0.81), "
                                              "50x (0.32), 100x (0.16)")
      ->capture_default_str();
  plan->add_option("--fov-mm", plan_args->job.fov_mm, "field of view in mm, instead of the lens table's")->check(Within(1e-3, 1e3, "mm"));
  AddHiddenAlias(plan, "--fov", plan_args->job.fov_mm, "--fov-mm");
  plan->add_option_function<std::string>(
          "--region",
          [plan_args](const std::string& text) {
            const auto r = ParseNumbers(text, 4, "--region", "--region 0,0,20,20 (x0,y0,x1,y1 in mm)");
            plan_args->job.region = imaging::Region{r[0], r[1], r[2], r[3]};
          },
          "x0,y0,x1,y1 in mm (default: the bounding box of the features)")
      ->check(NumbersCheck(4, "--region", "--region 0,0,20,20 (x0,y0,x1,y1 in mm)"));
  plan->add_option_function<std::string>(
          "--overlap",
          [plan_args](const std::string& text) { plan_args->job.overlap = imaging::ParseOverlap(text, "--overlap"); },
          "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->default_str("0.2");
  plan->add_option("--features", plan_args->job.features,
                   "centre export (CSV id,x,y,z[,radius], mm) of the features a stitching-free scan must cover");
  plan->add_option("--artefact", plan_args->job.artefact, "cover the calottes of a known artefact: grid6x6 or bar17, in "
                                                      "its own frame");
  plan->add_option("--radius-mm", plan_args->job.radius_mm, "feature radius in mm (overrides the file's or artefact's)")->check(Within(1e-3, 1e3, "mm"));
  AddHiddenAlias(plan, "--radius", plan_args->job.radius_mm, "--radius-mm");
  plan->add_option("--seconds-per-tile", plan_args->job.seconds_per_tile, "scan time per tile (s)")->check(Within(1e-3, 3600.0, "s"))->capture_default_str();
  plan->add_option("--tile-px", plan_args->tile_pixels, "pixels per tile, WxH")
      ->check(NumbersCheck(2, "--tile-px", "1024x1024", {16, 65536, "px", true}, 'x'))
      ->capture_default_str();
  AddHiddenAlias(plan, "--tile-pixels", plan_args->tile_pixels, "--tile-px");
  plan->add_option("--bytes-per-pixel", plan_args->job.bytes_per_pixel, "stored bytes per pixel (height + colour)")
      ->check(Count(1, 64))
      ->capture_default_str();
  plan->add_option("-o,--layout", plan_args->output, "write the stitched layout CSV file,row,col,x,y");
  plan->add_option("--free-layout", plan_args->free_output, "write the stitching-free layout CSV file,row,col,x,y");
  plan->add_flag("--calibration-scan", plan_args->job.calibration_scan,
                 "plan stitched calibration scans for fvm calibrate --scan instead: a row along X, a column along Y and "
                 "a diagonal through the travel's centre (any textured part; no artefact)");
  plan->add_option("--travel", plan_args->travel, "--calibration-scan: the stage travel WxH (mm), coordinates -W..0, -H..0")
      ->check(NumbersCheck(2, "--travel", "200x200", kTravelMm, 'x'))
      ->capture_default_str();
  plan->add_option("--length-mm", plan_args->job.length_mm, "--calibration-scan: length of each path")->check(Within(kStepMm))->capture_default_str();
  plan->add_option("--heights", plan_args->heights, "--calibration-scan: encoder z of each set of paths (mm), e.g. -50,-40")
      ->check(NumbersCheck(0, "--heights", "-50,-40"))
      ->capture_default_str();
  plan->add_option("--scan-dir", plan_args->job.scan_dir, "--calibration-scan: write each path's layout (file,row,col,x,y,z) here");
  plan->add_flag("--json", plan_args->json,
                 "print one JSON document {\"fov_mm\", \"overlap\", \"step_mm\", \"region\", \"stitched\": {\"rows\", "
                 "\"cols\", \"tiles\", \"seconds\", \"bytes\"}, \"stitching_free\": {\"tiles\", \"seconds\", \"bytes\", "
                 "\"features\"} or null}");
  plan->footer(
      "Tiles are squares of the field of view on a lattice of step field x (1 - overlap), anchored at the region's "
      "lowest X and highest Y, where the instrument starts; row 0 is the highest Y, column 0 the lowest X. The scan "
      "takes column after column from -X to +X, each from +Y to -Y. A stitching-free scan takes only the grid tiles "
      "that hold each feature whole.\n"
      "Example (the published 6 x 6 grid, 225 vs 49 tiles):\n  fvm tiles plan --lens 10x --artefact grid6x6 "
      "--overlap 13\n"
      "Calibration scans over 150 mm with the 5x lens:\n  fvm tiles plan --calibration-scan --lens 5x --overlap 25 "
      "--scan-dir scans");
  plan->callback([plan_args] { RunPlan(*plan_args); });

  AddTilesSynthesize(tiles);
  AddTilesSimulate(tiles);
}

}  // namespace fvm::cli
