// fvm compare BATCH [--models 9,15,27,42]: every model order side by side, and which one to trust.

#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include "artefacts/io/batch.h"
#include "core/input_error.h"
#include "fvm/identify_options.h"
#include "workflows/compare_models.h"
#include "fvm/commands.h"
#include "stage/fvm_stage_models.h"
#include "stage/validation.h"

namespace fvm::cli {
namespace {

struct CompareArgs {
  std::string batch;
  std::vector<std::string> models = stage::FvmModelNames();
  bool json = false;
  workflows::IdentifySettings settings;
};

void Run(const CompareArgs& args) {
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  const workflows::ModelComparison comparison =
      workflows::CompareModels(batch, args.models, Threaded(args.settings), [&](const std::string& model) {
        if (!args.json) fmt::print(stderr, "  identifying model {} ...\n", model);
      });
  const std::vector<workflows::ModelScore>& scores = comparison.scores;
  const std::string& recommendation = comparison.recommendation;
  nlohmann::json doc;
  doc["batch"] = args.batch;
  doc["validation_by"] = batch.validate.empty() ? "leave-one-placement-out" : "batch.json validate placements";
  doc["stitched_frame"] = args.settings.stitched_frame;
  const auto frame_free = [](const stage::FrameFreeStats& s) {
    return nlohmann::json{{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
                          {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
  };
  for (const workflows::ModelScore& s : scores) {
    const stage::IdentificationResult& id = s.identification;
    doc["models"].push_back({{"model", s.model},
                             {"n_params", s.nominal},
                             {"n_identified", id.calibration.layout.NumFree()},
                             {"fixed", id.fixed.size()},
                             {"identification", {{"mean_um", id.residual_summary.mean_um()}, {"rms_um", id.residual_summary.rms_um()}, {"max_um", id.residual_summary.max_um()}}},
                             {"validation",
                              {{"centres", s.validation.count},
                               {"mean_um", s.validation.mean_mm * 1e3},
                               {"rms_um", s.validation.rms_mm * 1e3},
                               {"max_um", s.validation.max_mm * 1e3},
                               {"predicted_rms_um", s.validation.predicted_rms_mm * 1e3},
                               {"rigid", frame_free(s.rigid)},
                               {"distances", frame_free(s.distances)}}},
                             {"distance_error_um", {{"rms", s.distance_error_rms_mm * 1e3}}},
                             {"aic", s.aic},
                             {"bic", s.bic},
                             {"condition", id.condition_number},
                             {"converged", id.converged}});
  }
  doc["recommendation"] = recommendation;
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("fvm compare: {} (validation: {})\n\n", args.batch, doc["validation_by"].get<std::string>());
  // Frame-free figures first: the rigid fit per placement and the distances over all pairs, then the first tile's.
  fmt::print("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "model", "params",
             "fixed", "id rms", "rigid", "predicted", "dist", "predicted", "1st-tile", "max", "predicted", "AIC", "BIC", "cond");
  fmt::print("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "", "", "", "um",
             "rms um", "rms um", "rms um", "rms um", "rms um", "um", "rms um", "", "", "");
  for (const workflows::ModelScore& s : scores) {
    const stage::IdentificationResult& id = s.identification;
    fmt::print("  {:>5} {:>6} {:>6} | {:>8.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>8.2f} {:>9.2f} | {:>9.1f} {:>9.1f} "
               "{:>8.3g}\n",
               s.model, s.nominal, id.fixed.size(), id.residual_summary.rms_um(), s.rigid.rms_mm * 1e3, s.rigid.predicted_rms_mm * 1e3,
               s.distances.rms_mm * 1e3, s.distances.predicted_rms_mm * 1e3, s.validation.rms_mm * 1e3,
               s.validation.max_mm * 1e3, s.validation.predicted_rms_mm * 1e3, s.aic, s.bic, id.condition_number);
  }
  fmt::print("  (first tile: each placement in its first tile's {} frame)\n", args.settings.stitched_frame);
  fmt::print("\n  {}\n", recommendation);
}

}  // namespace

void RegisterCompare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = app.add_subcommand("compare", "every model order side by side on a batch, and which one to trust");
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help')")->required();
  sub->add_option("--models", args->models, "models to compare")->delimiter(',')->check(CLI::IsMember(stage::FvmModelNames()));
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  AddIdentifyOptions(*sub, args->settings);
  sub->footer("Example:\n  fvm compare samples/bar17 --models 15,27,42");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
