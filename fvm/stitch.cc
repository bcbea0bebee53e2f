// fvm stitch: register the tiles of a layout (workflows/stitch_layout.h) and write their positions.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "core/file_io.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "fvm/distortion_options.h"
#include "imaging/tile_plan.h"
#include "report/report.h"
#include "workflows/field_distortion_file.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"

namespace fvm::cli {
namespace {

struct StitchArgs {
  std::string layout;
  std::string output;
  std::string mosaic;
  std::string report;
  bool json = false;
  workflows::StitchLayoutOptions job;
  DistortionArgs distortion;
};

// The distortion options as the workflow takes them: an order to identify, or the saved field.
void BindDistortion(StitchArgs& args) {
  args.distortion.Check();
  if (!args.distortion.Requested()) return;
  workflows::StitchDistortionOptions field;
  field.order = args.distortion.Order();
  field.known = args.distortion.Known();
  args.job.distortion = field;
}

// What the tiles and the field write: the saved field, the undistorted tiles, the positions, the mosaic.
void WriteOutputs(const StitchArgs& args, const workflows::LayoutTiles& tiles, const workflows::StitchedLayout& stitched) {
  if (stitched.field && !args.distortion.save.empty()) {
    workflows::WriteFieldDistortion(args.distortion.save, stitched.field->fit.field, stitched.options.pixel_mm);
  }
  if (stitched.field && !args.distortion.undistorted_dir.empty()) {
    workflows::WriteUndistortedTiles(args.distortion.undistorted_dir, stitched, tiles.images, tiles.pixel_type);
  }
  WriteFileAtomically(args.output, workflows::IsFijiPositionsPath(args.output) ? workflows::PositionsFiji(stitched)
                                                                               : workflows::PositionsCsv(stitched));
  if (args.mosaic.empty()) return;
  Progress tile_progress("fusing tiles", static_cast<int>(tiles.images.size()), ShowProgress());
  imaging::Mosaic mosaic = workflows::FuseStitched(stitched, tiles.images, [&](int, int) { tile_progress.Advance(); });
  tile_progress.Finish();
  workflows::WriteMosaic(args.mosaic, std::move(mosaic), stitched, tiles.pixel_type);
}

void RunStitch(StitchArgs& args) {
  args.job.stitch.threads = ThreadCount();
  args.job.Check();
  workflows::CheckMosaicPath(args.mosaic, args.job.stitch.pixel_mm);
  BindDistortion(args);
  const workflows::LayoutTiles tiles = workflows::ReadLayoutTiles(args.layout, args.job.stitch.threads, args.job.stitch.overlap);
  workflows::CheckMosaicTiles(args.mosaic, tiles.pixel_type);
  Progress pair_progress("registering pairs", workflows::StitchPairCount(tiles.layout, tiles.images, args.job.stitch),
                         ShowProgress());
  const workflows::StitchedLayout stitched =
      workflows::StitchLayout(tiles.layout, tiles.images, args.job, [&](int, int) { pair_progress.Advance(); });
  pair_progress.Finish();
  WriteOutputs(args, tiles, stitched);
  // What the loops overruled, and a run that leaves a quarter of its pairs unresolved, go to stderr whatever the
  // output: a script reading --json sees them there too.
  const workflows::StitchResult& placed = stitched.Registered();
  for (const auto& text : placed.overruled) fmt::print(stderr, "fvm stitch: overruled {}\n", text);
  if (placed.mostly_unresolved) fmt::print(stderr, "fvm stitch: warning: {}\n", placed.UnresolvedWarning());
  const workflows::Summary summary = workflows::Summarize(stitched);
  if (!args.report.empty()) report::Write(args.report, *summary.report);
  if (args.json) {
    fmt::print("{}\n", summary.json.dump(2));
    return;
  }
  fmt::print("{}positions written to {}{}{}\n", summary.text, args.output,
             args.mosaic.empty() ? "" : ", mosaic to " + args.mosaic,
             args.report.empty() ? "" : ", report to " + args.report + "/index.html");
}

}  // namespace

void RegisterStitch(CLI::App& app) {
  auto args = std::make_shared<StitchArgs>();
  CLI::App* sub = app.add_subcommand("stitch", "register overlapping tiles");
  AddDetails(sub,
      "Registers every tile with its right and lower neighbour: the overlap's normalised cross-correlation at every "
      "offset within a quarter of a tile of the nominal one (by Fourier transforms, on a pyramid level), its one "
      "clear peak refined to sub-pixel with the pair's uncertainty; where it has none (a repeating pattern, a "
      "ridge along marks), the phase correlation of the nominal overlap. Tiles that match one on the other better "
      "than anywhere the stage allows (the same image twice) register nothing. Thin overlaps (under 24 px), and the pairs that fail when "
      "too few pass to estimate the stage, are searched instead: phase-correlation candidates within 10 % of a tile "
      "of the nominal offset, each tested by the normalised cross-correlation of the overlap it implies, the best "
      "refined. From the pairs that pass it estimates the stage (step and "
      "sideways drift per column and row, repeatability), searches the failed and disagreeing pairs again within a "
      "few repeatabilities of it, and takes its positions as the stage prior; solves all positions by least squares weighted by those "
      "uncertainties, and writes file,x,y: each tile's top-left corner in pixels (x right, y down), the first tile "
      "of the layout at 0,0, with its standard uncertainty. Tiles that no good pair links to an earlier one keep "
      "their stage (or grid) positions, as the instrument does; along parallel marks, where images cannot tell a "
      "shift, the stage position holds too.");
  sub->add_option("--layout", args->layout,
                  "layout CSV file,row,col[,x,y], or a Fiji tile configuration (TileConfiguration.txt: 'dim = 2', then "
                  "'name; ; (x, y)' in px; rows and columns found by clustering the positions with the tile size "
                  "times 1 - overlap; the positions are the nominal ones); image paths relative to it")
      ->required();
  sub->add_option_function<std::string>(
         "--overlap", [args](const std::string& text) { args->job.stitch.overlap = imaging::ParseOverlap(text, "--overlap"); },
                  "nominal overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: "
                  "0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->required();
  sub->add_option("-o,--output", args->output,
                  "positions CSV file,x,y[,x_mm,y_mm],registered,u_x,u_y (u: standard uncertainty in px against "
                  "the first tile of the chain); a name ending in .txt writes the same positions as Fiji's registered "
                  "tile configuration ('name; ; (x, y)', px), which Fiji's Grid/Collection stitching opens")
      ->required();
  sub->add_option("--mosaic", args->mosaic,
                  "also fuse the registered tiles (feathered seams) into one image in the tiles' pixel type (TIFF, "
                  "PNG, EXR; NaN or 0 where no tile reaches), or into an X3P height map in the stage frame when the "
                  "name ends in .x3p (float tiles holding heights in mm; needs --pixel-mm)");
  sub->add_option("--pixel-mm", args->job.stitch.pixel_mm,
                  "pixel size in mm: adds x_mm,y_mm (stage frame, +Y up) and takes nominal positions from the "
                  "layout's x,y")
      ->check(Within(kPixelMm));
  sub->add_option("--min-quality", args->job.stitch.registration.min_quality, "reject pairs whose aligned correlation is below this")
      ->check(Within(-1.0, 1.0))
      ->capture_default_str();
  sub->add_option("--stage-sigma-px", args->job.stitch.registration.stage_sigma_px,
                  "the stage's positioning error over the grid (px, standard deviation): what holds a tile along a "
                  "direction its images do not determine")
      ->check(Within(1e-3, 1e4, "px"))
      ->capture_default_str();
  AddHiddenAlias(sub, "--stage-sigma", args->job.stitch.registration.stage_sigma_px, "--stage-sigma-px");
  AddDistortionOptions(sub, &args->distortion, true);
  sub->add_option("--report", args->report,
                  "write an HTML report into this directory: the tiles where they were placed with their u, every pair "
                  "(accepted, overruled by the loops, unresolved), the loops' misclosures and, with --distortion, the "
                  "field (terms with u, a plot of its displacement across a tile, overlap NCC before and after)");
  sub->add_flag("--json", args->json,
                "print one JSON document {\"tiles\", \"pairs_accepted\", \"pairs_ambiguous\", \"mean_overlap_ncc\", "
                "\"pairs_unresolved\", \"unresolved_warning\" (null unless a quarter of the pairs or more), \"overruled\": "
                "[{\"a\", \"b\", \"registered_px\", \"predicted_px\", \"misclosure_sigma\", \"replaced\"}] (pairs the "
                "grid's loops contradicted, also on stderr), \"loop_birge_ratio\", \"loop_dof\", \"stage_fallback\": [files], "
                "\"stage_along_one_axis\": [files], \"without_neighbour\": [\"FILE (row R col C)\"] (tiles the layout's holes leave without a "
                "side neighbour: registered through their corners with diagonal ones), \"stage_model\": {\"east_step_px\", \"east_drift_px\", "
                "\"south_step_px\", \"south_drift_px\", \"repeatability_px\", \"shared\": {\"column_step_px\", \"row_step_px\", "
                "\"own_px\"} (the stage's error shared along columns and rows, and each tile's own), ...}, \"pairs\": [{\"a\", \"b\", "
                "\"dx_px\", \"dy_px\", \"sigma_px\", \"quality\", \"accepted\", \"overlap_ncc\", \"ambiguous\", \"unmoved\", \"candidates\": [{\"dx_px\", "
                "\"dy_px\", \"peak\", \"ncc\"}]}]}; with --distortion, when pairs the raw tiles did not register "
                "registered on the undistorted tiles, the pairs, loops, stage model and fallbacks are that registration's "
                "(the overlap NCC stays the raw tiles' at the rigid positions)");
  sub->footer("Examples:\n  fvm tiles synthesize -o demo --seed 1 && fvm stitch --layout demo/layout.csv --overlap 20 "
              "-o demo/positions.csv --mosaic demo/mosaic.tif\n"
              "  fvm stitch --layout demo/layout.csv --overlap 20 -o demo/positions.csv --distortion --report demo/report");
  sub->callback([args] { RunStitch(*args); });
}

}  // namespace fvm::cli
