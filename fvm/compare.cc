// fvm compare BATCH [--models 9,15,27,42]: every model order side by side, and which one to trust.

#include <fmt/core.h>

#include "artefacts/io/batch.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/identify_options.h"
#include "stage/fvm_stage_models.h"
#include "workflows/compare_models.h"

namespace fvm::cli {
namespace {

struct CompareArgs {
  std::string batch;
  bool json = false;
  workflows::CompareOptions options;
};

void Run(const CompareArgs& args) {
  workflows::CompareOptions options = args.options;
  options.settings = Threaded(options.settings);
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  const workflows::ModelComparison comparison = workflows::CompareModels(batch, options, [&](const std::string& model) {
    if (!args.json) fmt::print(stderr, "  identifying model {} ...\n", model);
  });
  workflows::Summary summary = workflows::Summarize(comparison, options, args.batch);
  if (args.json) {
    AddSortedPath(summary.json, "batch", args.batch);
    fmt::print("{}\n", summary.json.dump(2));
  } else {
    fmt::print("{}", summary.text);
  }
}

}  // namespace

void RegisterCompare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = app.add_subcommand("compare", "every model order side by side on a batch, and which one to trust");
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help')")->required();
  sub->add_option("--models", args->options.models, "models to compare")
      ->delimiter(',')
      ->check(CLI::IsMember(stage::FvmModelNames()));
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  AddIdentifyOptions(*sub, args->options.settings);
  sub->footer("Example:\n  fvm compare samples/bar17 --models 15,27,42");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
