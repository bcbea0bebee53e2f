// fvm simulate fvm-batch -o DIR: a synthetic calibration batch with its recorded truth.

#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include "core/file_io.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "fvm/commands.h"
#include "stage/fvm_stage_models.h"

namespace fvm::cli {
namespace {

struct SimulateBatchArgs {
  std::string output;
  artefacts::FvmBatchOptions options;
  bool different_starts = false;
};

void Run(SimulateBatchArgs args) {
  args.options.same_start = !args.different_starts;
  const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(args.options);
  artefacts::WriteBatch(args.output, sim.batch);

  nlohmann::json truth;
  truth["what"] = "stage error model the batch was simulated with (fvm simulate fvm-batch)";
  truth["model"] = args.options.truth_model;
  truth["seed"] = args.options.seed;
  truth["noise_um"] = args.options.noise_um;
  truth["pitch_error_um"] = args.options.pitch_error_um;
  truth["same_start"] = args.options.same_start;
  truth["height_step_mm"] = args.options.height_step_mm;
  truth["hidden_effect"] = args.options.hidden_effect.empty() ? nlohmann::json(nullptr) : nlohmann::json(args.options.hidden_effect);
  truth["effect_size"] = args.options.effect_size;
  truth["mean_error_um"] = sim.truth.mean_error_um;
  truth["max_error_um"] = sim.truth.max_error_um;
  const std::vector<std::string> names = sim.truth.layout.FreeNames();
  for (size_t i = 0; i < names.size(); ++i) {
    const auto& c = sim.truth.layout.coefficients()[static_cast<size_t>(sim.truth.layout.FindCoefficient(names[i]))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    truth["parameters"].push_back({{"name", names[i]}, {"value", sim.truth.values[i]},
                                   {std::string("value_") + unit.name, sim.truth.values[i] * unit.per_si}});
  }
  WriteFileAtomically(std::filesystem::path(args.output) / "truth.json", truth.dump(2) + "\n");
  size_t centres = 0;
  for (const auto& p : sim.batch.placements) centres += p.ids.size();
  fmt::print("simulated {} placements ({} centres) into {}: truth model {}, mean stage error {:.1f} um (max {:.1f} um), "
             "noise {} um, seed {}\n",
             sim.batch.placements.size(), centres, args.output, args.options.truth_model, sim.truth.mean_error_um,
             sim.truth.max_error_um, args.options.noise_um, args.options.seed);
}

}  // namespace

void RegisterSimulate(CLI::App& app) {
  CLI::App* simulate = app.add_subcommand("simulate", "synthetic data with a recorded truth (batches so far)");
  simulate->require_subcommand(1);
  simulate->footer("Example:\n  fvm simulate fvm-batch -o batch --seed 7 && fvm calibrate batch --model 27");
  auto args = std::make_shared<SimulateBatchArgs>();
  CLI::App* sub = simulate->add_subcommand(
      "fvm-batch", "17-calotte bar placements on the 200 x 200 mm stage (X, Y, oblique to identify; random to "
                   "validate), stitched and stitching-free, plus truth.json");
  sub->add_option("-o,--output", args->output, "batch directory to write")->required();
  sub->add_option("--seed", args->options.seed, "random seed (same seed, same bytes)")->capture_default_str();
  sub->add_option("--truth-model", args->options.truth_model, "stage error model of the truth")
      ->check(CLI::IsMember(stage::FvmModelNames()))
      ->capture_default_str();
  sub->add_option("--mean-error-um", args->options.mean_error_um, "mean stage error over the stage (um)")->capture_default_str();
  sub->add_option("--noise-um", args->options.noise_um, "centre noise per coordinate (um)")->capture_default_str();
  sub->add_option("--validation-placements", args->options.validation_placements, "number of validation placements")
      ->capture_default_str();
  sub->add_option("--pitch-error-um", args->options.pitch_error_um, "calotte deviations of the uncalibrated bar (um)")
      ->capture_default_str();
  sub->add_option("--hidden-effect", args->options.hidden_effect,
                  "hide one effect the stage model lacks, for 'fvm diagnose' (sizes: see --effect-size)")
      ->check(CLI::IsMember(artefacts::HiddenEffectNames()));
  sub->add_option("--effect-size", args->options.effect_size,
                  "size of the hidden effect; 0 = default: thermal_drift 3 um/min, higher_order 80 um, reference_anchor "
                  "30 mm, z_coupling 500 urad, outliers 80 um, scale 300 ppm")
      ->capture_default_str();
  sub->add_option("--height-step-mm", args->options.height_step_mm,
                  "the bar lies on a wedge rising by -step, 0, +step over its length, placement by placement")
      ->capture_default_str();
  sub->add_flag("--different-starts", args->different_starts,
                "identification placements do not share their first calotte's spot (needs --anchor first-tile)");
  sub->footer("Example:\n  fvm simulate fvm-batch -o batch --seed 7 --noise-um 0.5");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
