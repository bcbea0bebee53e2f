// fvm diagnose BATCH --model N: the discrepancy workflow (stage/discrepancy.h) from the command line; on tiles
// (--layout, --scan) the field distortion's test (workflows/diagnose_tiles.h).

#include <fmt/core.h>

#include "artefacts/io/batch.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/identify_options.h"
#include "imaging/tile_plan.h"
#include "report/report.h"
#include "workflows/diagnose.h"
#include "workflows/diagnose_tiles.h"

namespace fvm::cli {
namespace {

struct DiagnoseArgs {
  std::string batch;
  std::string report;
  bool json = false;
  workflows::DiagnoseOptions options;
  workflows::TileDiagnoseOptions tiles;  // --layout / --scan
  std::string overlap;                   // --overlap as given
};

void RunTiles(const DiagnoseArgs& args) {
  workflows::TileDiagnoseOptions options = args.tiles;
  if (!args.overlap.empty()) options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.alpha = args.options.alpha;
  options.threads = ThreadCount();
  if (!args.report.empty()) {
    throw CLI::ValidationError("--report", "is for a batch; the field of a tile set is drawn by fvm stitch --distortion --report");
  }
  workflows::Summary summary = workflows::Summarize(workflows::DiagnoseTiles(options), options);
  if (args.json) {
    if (!options.layout.empty()) summary.json["layout"] = options.layout;
    fmt::print("{}\n", summary.json.dump(2));
    return;
  }
  fmt::print("{}", summary.text);
}

void Run(const DiagnoseArgs& args) {
  const bool tiles = !args.tiles.layout.empty() || !args.tiles.scans.empty();
  if (args.batch.empty() == !tiles || (!args.tiles.layout.empty() && !args.tiles.scans.empty())) {
    throw CLI::ValidationError("BATCH", "give a BATCH directory, or tiles: --layout L.csv (one grid) or --scan L.csv "
                                        "(calibration scans), one of them");
  }
  if (tiles) return RunTiles(args);
  workflows::DiagnoseOptions options = args.options;
  options.settings = Threaded(options.settings);
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  workflows::Summary summary = workflows::Summarize(workflows::DiagnoseBatch(batch, options), options, args.batch);
  if (!args.report.empty()) report::Write(args.report, *summary.report);
  if (args.json) {
    AddSortedPath(summary.json, "batch", args.batch);
    fmt::print("{}\n", summary.json.dump(2));
    return;
  }
  fmt::print("{}", summary.text);
  if (!args.report.empty()) fmt::print("\nreport written to {}/index.html\n", args.report);
}

}  // namespace

void RegisterDiagnose(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArgs>();
  workflows::DiagnoseOptions& options = args->options;
  CLI::App* sub = app.add_subcommand(
      "diagnose", "find where model and measurements disagree, name the missing effect, add it, show the gap shrink");
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help'); held-out placements confirm");
  sub->add_option("--layout", args->tiles.layout,
                  "instead of a batch: a grid of tiles as fvm stitch takes it (file,row,col[,x,y]; needs --overlap): "
                  "is the objective's field distortion in its overlaps?");
  sub->add_option("--scan", args->tiles.scans,
                  "instead of a batch: calibration scans as fvm calibrate --scan takes them (repeat; needs --pixel-mm): "
                  "is the objective's field distortion in their overlaps?");
  sub->add_option("--overlap", args->overlap, "--layout: the tiles' nominal overlap in percent (as fvm stitch)");
  sub->add_option("--pixel-mm", args->tiles.pixel_mm, "--layout, --scan: the pixel size on the part (mm): sizes also in um")
      ->check(Within(kPixelMm));
  sub->add_option("--order", args->tiles.order, "--layout, --scan: the field model's polynomial order (2..6)")
      ->check(Count(2, imaging::kMaxDistortionOrder))
      ->capture_default_str();
  sub->add_option("--model", options.model.model, "base model: 9, 15, 27 or 42")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", options.model.terms, "a base model of one's own instead: TERM[:BASIS][:ORDER],... as 'fvm calibrate --terms'");
  sub->add_option("--alpha", options.alpha, "family-wise false-alarm probability of the selection")
      ->check(Within(1e-6, 0.5))
      ->capture_default_str();
  sub->add_option("--report", args->report, "write residual plots before and after into this directory (HTML)");
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  // The workflow starts from the translation-only frame (DiagnoseOptions' default), so that a turn of the stitched
  // frames shows up on the held-out placements as the frame_rotation effect, named and sized, instead of being
  // hidden by the model's.
  AddIdentifyOptions(*sub, options.settings);
  sub->footer("The stitched frame defaults to 'translated' here (not 'rotated' as in calibrate): the diagnosis starts from "
              "the plainest convention, so that a turn of each stitched export about its first tile is found and named "
              "(frame_rotation).\n"
              "On tiles (--layout, --scan), dense correspondences in every registered overlap are fitted twice on the same "
              "points, a rigid image of every tile and one field distortion of the objective for all "
              "(fvm stitch --distortion's model); an F test of the field's extra coefficients, its noise the "
              "correspondences' scatter widened by how much more a quarter of an overlap scatters, names "
              "field_distortion with its largest displacement and the overlap residuals before and after.\n"
              "Examples:\n  fvm simulate fvm-batch -o drift --hidden-effect thermal_drift && fvm diagnose drift --model 27\n"
              "  fvm simulate scan -o scans --distortion 2 && fvm diagnose --scan scans/row.csv --scan scans/column.csv "
              "--pixel-mm 0.00275");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
