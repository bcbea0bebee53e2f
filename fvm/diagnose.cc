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
  // Options of one mode only, refused in the other (a user passing them expects an effect they cannot have there).
  std::vector<const CLI::Option*> batch_only, tiles_only;
};

// The first option of `options` the user gave, or nullptr.
const CLI::Option* FirstGiven(const std::vector<const CLI::Option*>& options) {
  for (const CLI::Option* option : options) {
    if (option->count() > 0) return option;
  }
  return nullptr;
}

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
  // The tiles' test compares a rigid image of every tile with one field distortion of the objective, both on the
  // overlaps alone: no stage model takes part (the tiles' positions are free), so --model, --terms and the
  // identification settings have nothing to act on; the field's own model is --order. Conversely a batch's centres
  // hold no overlaps.
  if (tiles) {
    if (const CLI::Option* given = FirstGiven(args.batch_only)) {
      throw CLI::ValidationError(
          given->get_name(),
          "is for a batch's stage model; on tiles (--layout, --scan) diagnose tests the objective's field distortion "
          "on the overlaps alone, with the tiles' positions free, so no stage model takes part (the field's model is "
          "--order). The stage model from scans: fvm calibrate --scan ... --model N --distortion");
    }
    return RunTiles(args);
  }
  if (const CLI::Option* given = FirstGiven(args.tiles_only)) {
    throw CLI::ValidationError(given->get_name(),
                               "is for tiles (--layout, --scan): a batch's centres hold no overlaps to test a field "
                               "distortion on; the batch's model is --model or --terms");
  }
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
  const CLI::Option* overlap =
      sub->add_option("--overlap", args->overlap, "--layout: the tiles' nominal overlap in percent (as fvm stitch)");
  const CLI::Option* pixel_mm =
      sub->add_option("--pixel-mm", args->tiles.pixel_mm,
                      "--layout, --scan: the pixel size on the part (mm): sizes also in um")
          ->check(Within(kPixelMm));
  const CLI::Option* order =
      sub->add_option("--order", args->tiles.order, "--layout, --scan: the field model's polynomial order (2..6)")
          ->check(Count(2, imaging::kMaxDistortionOrder))
          ->capture_default_str();
  const CLI::Option* model =
      sub->add_option("--model", options.model.model, "a batch's base model: 9, 15, 27 or 42 (refused on tiles)")
          ->check(CLI::IsMember({"9", "15", "27", "42"}))
          ->capture_default_str();
  const CLI::Option* terms = sub->add_option(
      "--terms", options.model.terms,
      "a batch's base model of one's own instead: TERM[:BASIS][:ORDER],... as 'fvm calibrate --terms' "
      "(refused on tiles)");
  sub->add_option("--alpha", options.alpha, "family-wise false-alarm probability of the selection")
      ->check(Within(1e-6, 0.5))
      ->capture_default_str();
  sub->add_option("--report", args->report, "write residual plots before and after into this directory (HTML)");
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  // The workflow starts from the translation-only frame (DiagnoseOptions' default), so that a turn of the stitched
  // frames shows up on the held-out placements as the frame_rotation effect, named and sized, instead of being
  // hidden by the model's.
  AddIdentifyOptions(*sub, options.settings);
  args->tiles_only = {overlap, pixel_mm, order};
  args->batch_only = {model, terms, sub->get_option("--anchor"), sub->get_option("--stitched-frame"),
                      sub->get_option("--loss"), sub->get_option("--loss-scale-um")};
  sub->footer("The stitched frame defaults to 'translated' here (not 'rotated' as in calibrate): the diagnosis starts from "
              "the plainest convention, so that a turn of each stitched export about its first tile is found and named "
              "(frame_rotation).\n"
              "On tiles (--layout, --scan), dense correspondences in every registered overlap are fitted twice on the same "
              "points, a rigid image of every tile and one field distortion of the objective for all "
              "(fvm stitch --distortion's model); an F test of the field's extra coefficients, its noise the "
              "correspondences' scatter widened by how much more a quarter of an overlap scatters, names "
              "field_distortion with its largest displacement and the overlap residuals before and after. No stage model takes "
              "part (the tiles' positions are free): on tiles --model, --terms, --anchor, --stitched-frame, --loss and "
              "--loss-scale-um are refused, and on a batch --overlap, --pixel-mm and --order.\n"
              "Examples:\n  fvm simulate fvm-batch -o drift --hidden-effect thermal_drift && fvm diagnose drift --model 27\n"
              "  fvm simulate scan -o scans --distortion 2 && fvm diagnose --scan scans/row.csv --scan scans/column.csv "
              "--pixel-mm 0.00275");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
