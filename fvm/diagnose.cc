// fvm diagnose BATCH --model N: the discrepancy workflow (stage/discrepancy.h) from the command line.

#include <fmt/core.h>

#include "artefacts/io/batch.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/identify_options.h"
#include "report/report.h"
#include "workflows/diagnose.h"

namespace fvm::cli {
namespace {

struct DiagnoseArgs {
  std::string batch;
  std::string report;
  bool json = false;
  workflows::DiagnoseOptions options;
};

void Run(const DiagnoseArgs& args) {
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
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help'); held-out placements confirm")
      ->required();
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
              "Example:\n  fvm simulate fvm-batch -o drift --hidden-effect thermal_drift && fvm diagnose drift --model 27");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
