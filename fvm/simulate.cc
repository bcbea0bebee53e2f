// fvm simulate: synthetic data with a recorded truth. This file holds the command and fvm simulate fvm-batch -o DIR
// (a synthetic calibration batch, workflows/simulate_batch.h); its other subcommands register themselves from
// simulate_tracker.cc, simulate_scan.cc and the test piece's file.

#include <fmt/core.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "fvm/commands.h"
#include "stage/fvm_stage_models.h"
#include "workflows/simulate_batch.h"

namespace fvm::cli {
namespace {

struct SimulateBatchArgs {
  std::string output;
  workflows::SimulateBatchOptions options;
};

}  // namespace

void RegisterSimulate(CLI::App& app) {
  CLI::App* simulate =
      app.add_subcommand("simulate", "synthetic data with a recorded truth (FVM batches, machine-tool tracker readings)");
  simulate->require_subcommand(1);
  simulate->footer("Examples:\n  fvm simulate fvm-batch -o batch --seed 7 && fvm calibrate batch --model 27\n"
                   "  fvm simulate tracker -o plan --seed 1 --validation mesh:100,100,100");
  auto args = std::make_shared<SimulateBatchArgs>();
  CLI::App* sub = simulate->add_subcommand(
      "fvm-batch", "17-calotte bar placements on the 200 x 200 mm stage (X, Y, oblique to identify; random to "
                   "validate), stitched and stitching-free, plus truth.json");
  sub->add_option("-o,--output", args->output, "batch directory to write")->required();
  sub->add_option("--seed", args->options.batch.seed, "random seed (same seed, same bytes)")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--truth-model", args->options.batch.truth_model, "stage error model of the truth")
      ->check(CLI::IsMember(stage::FvmModelNames()))
      ->capture_default_str();
  sub->add_option("--truth-terms", args->options.batch.truth_terms,
                  "a truth of one's own form instead: TERM[:BASIS][:ORDER],... as 'fvm calibrate --terms'");
  sub->add_option("--mean-error-um", args->options.batch.mean_error_um, "mean stage error over the stage (um)")
      ->check(Within(0.0, 1e4, "um"))
      ->capture_default_str();
  sub->add_option("--noise-um", args->options.batch.noise_um, "centre noise per coordinate (um)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--validation-placements", args->options.batch.validation_placements, "number of validation placements")
      ->check(Count(0, 1000))
      ->capture_default_str();
  sub->add_option("--pitch-error-um", args->options.batch.pitch_error_um, "calotte deviations of the uncalibrated bar (um)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--hidden-effect", args->options.batch.hidden_effect,
                  "hide effects the stage model lacks, for 'fvm diagnose': one name or several joined by commas, e.g. "
                  "thermal_drift,scale (sizes: see --effect-size)")
      ->check(CLI::Validator(
          [](std::string& value) {
            artefacts::FvmBatchOptions o;
            o.hidden_effect = value;
            try {
              o.Check();
            } catch (const std::invalid_argument& e) {
              return std::string(e.what());
            }
            return std::string();
          },
          "EFFECT[,EFFECT...]"));
  sub->add_option("--effect-size", args->options.batch.effect_size,
                  "size of the hidden effect; 0 = default: thermal_drift 3 um/min, higher_order 80 um, reference_anchor "
                  "30 mm, z_coupling 500 urad (X; Y half), outliers 80 um, scale 300 ppm")
      ->check(Within(0.0, 1e5))
      ->capture_default_str();
  sub->add_option("--drift-tau-min", args->options.batch.drift_tau_min,
                  "thermal_drift: 0 drifts linearly in t; > 0 a warm-up B (1 - exp(-t/tau)) with this time constant (min)")
      ->check(Within(0.0, 1e4, "min"))
      ->capture_default_str();
  sub->add_option("--periodic-um", args->options.batch.periodic_um,
                  "a lead screw's cyclic error along X and Y that no polynomial model takes (um; 0: none)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--period-mm", args->options.batch.period_mm, "its period")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--height-step-mm", args->options.batch.height_step_mm,
                  "the bar lies on a wedge rising by -step, 0, +step over its length, placement by placement")
      ->check(Within(0.0, 100.0, "mm"))
      ->capture_default_str();
  sub->add_flag("--serpentine", args->options.batch.serpentine,
                "measure every other placement from its last calotte back to its first, so that a drift shows at the "
                "shared start (on a wedge, drift and pitch and roll are otherwise confounded)");
  sub->add_flag("--different-starts", args->options.different_starts,
                "identification placements do not share their first calotte's spot (needs --anchor first-tile)");
  sub->add_option("--stitched-frame", args->options.stitched_frame,
                  "rotated: each stitched export keeps the orientation of its first tile, turned with the stage there, "
                  "as an instrument that registers tiles by translation does (default); translated: the turn left out")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  sub->add_option("--surfaces", args->options.surfaces,
                  "write each export as a height map of this format instead of a centre CSV (the bar's calottes where "
                  "the export places them, with height noise), the centre exports of the same simulation in "
                  "OUTPUT/centres; 'fvm calibrate OUTPUT' then searches the surfaces, e.g. --surfaces x3p")
      ->check(CLI::IsMember({"x3p", "tif"}));
  sub->add_option("--surface-pixel-mm", args->options.surface.pixel_mm,
                  "with --surfaces: pixel size of the surfaces (coarse: a 160 mm bar at 45 degrees is 2300 x 2300 "
                  "points at 0.05 mm), e.g. --surface-pixel-mm 0.1")
      ->check(Within(0.02, 0.5, "mm"))  // finer: a bar's mosaic of billions of points; coarser: no calotte left
      ->capture_default_str();
  sub->add_option("--surface-noise-um", args->options.surface.noise_um, "with --surfaces: height noise per pixel (um)")
      ->check(Within(0.0, 100.0, "um"))
      ->capture_default_str();
  sub->footer("Example:\n  fvm simulate fvm-batch -o batch --seed 7 --noise-um 0.5\n"
              "  fvm simulate fvm-batch -o raw --seed 7 --surfaces x3p && fvm calibrate raw --model 27");
  sub->callback([args] {
    fmt::print("{}", workflows::Summarize(workflows::SimulateBatch(args->options, args->output)).text);
  });
  RegisterSimulateTracker(simulate);
  RegisterSimulateScan(simulate);
  RegisterSimulateTestPiece(simulate);
}

}  // namespace fvm::cli
