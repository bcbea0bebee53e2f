// fvm simulate: synthetic data with a recorded truth. This file holds the command and fvm simulate fvm-batch -o DIR
// (a synthetic calibration batch); its other subcommands register themselves from simulate_tracker.cc,
// simulate_scan.cc and the test piece's file.

#include <fmt/core.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/raw_export_simulation.h"
#include "imaging/io/surface_file.h"
#include "core/file_io.h"
#include "workflows/model_choice.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "stage/fvm_stage_models.h"

namespace fvm::cli {
namespace {

struct SimulateBatchArgs {
  std::string output;
  artefacts::FvmBatchOptions options;
  bool different_starts = false;
  std::string stitched_frame = "rotated";
  std::string surfaces;  // x3p or tif (formats that carry the map's position): a batch of raw exports, the centre exports in OUTPUT/centres
  artefacts::RawExportSimulationOptions surface;
};

// The surfaces of every placement as FORMAT files in `dir`, the roles beside them, the centre exports of the same
// simulation (the CSV route) in dir/centres.
void WriteRawExports(const std::filesystem::path& dir, const SimulateBatchArgs& args, const artefacts::SimulatedFvmBatch& sim) {
  artefacts::WriteBatch(dir / "centres", sim.batch);
  artefacts::Batch roles = sim.batch;
  roles.placements.clear();
  artefacts::WriteBatch(dir, roles);  // batch.json alone
  for (std::size_t i = 0; i < sim.exact.placements.size(); ++i) {
    const artefacts::Placement& p = sim.exact.placements[i];
    const artefacts::RawExportPair maps = artefacts::RenderRawExports(p, i, args.surface);
    imaging::WriteHeightMap(dir / (p.name + ".stitched." + args.surfaces), maps.stitched);
    imaging::WriteHeightMap(dir / (p.name + ".free." + args.surfaces), maps.free);
  }
}

void Run(SimulateBatchArgs args) {
  args.options.same_start = !args.different_starts;
  args.options.stitched_frame = stage::ParseStitchedFrame(args.stitched_frame);
  args.surface.seed = args.options.seed;
  const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(args.options);
  if (args.surfaces.empty()) {
    artefacts::WriteBatch(args.output, sim.batch);
  } else {
    WriteRawExports(args.output, args, sim);
  }

  nlohmann::json truth;
  truth["what"] = "stage error model the batch was simulated with (fvm simulate fvm-batch)";
  truth["model"] = workflows::ModelChoice{args.options.truth_model, args.options.truth_terms}.Name();
  truth["seed"] = args.options.seed;
  truth["noise_um"] = args.options.noise_um;
  truth["pitch_error_um"] = args.options.pitch_error_um;
  truth["same_start"] = args.options.same_start;
  truth["height_step_mm"] = args.options.height_step_mm;
  truth["serpentine"] = args.options.serpentine;
  truth["periodic_um"] = args.options.periodic_um;
  truth["period_mm"] = args.options.period_mm;
  truth["stitched_frame"] = args.stitched_frame;
  if (!args.surfaces.empty()) {
    truth["surfaces"] = {{"format", args.surfaces}, {"pixel_mm", args.surface.pixel_mm},
                         {"height_noise_um", args.surface.noise_um}, {"centres", "centres/"}};
  }
  truth["hidden_effect"] = args.options.hidden_effect.empty() ? nlohmann::json(nullptr) : nlohmann::json(args.options.hidden_effect);
  truth["effect_size"] = args.options.effect_size;
  truth["drift_tau_min"] = args.options.drift_tau_min;
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
             sim.batch.placements.size(), centres, args.output, workflows::ModelChoice{args.options.truth_model, args.options.truth_terms}.Name(),
             sim.truth.mean_error_um,
             sim.truth.max_error_um, args.options.noise_um, args.options.seed);
  if (!args.surfaces.empty()) {
    fmt::print("surfaces: {} per placement, stitched and stitching-free ({} um pixel, {} um height noise); the "
               "centre exports of the same simulation in {}/centres\n",
               args.surfaces, args.surface.pixel_mm * 1e3, args.surface.noise_um, args.output);
  }
}


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
  sub->add_option("--seed", args->options.seed, "random seed (same seed, same bytes)")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--truth-model", args->options.truth_model, "stage error model of the truth")
      ->check(CLI::IsMember(stage::FvmModelNames()))
      ->capture_default_str();
  sub->add_option("--truth-terms", args->options.truth_terms,
                  "a truth of one's own form instead: TERM[:BASIS][:ORDER],... as 'fvm calibrate --terms'");
  sub->add_option("--mean-error-um", args->options.mean_error_um, "mean stage error over the stage (um)")
      ->check(Within(0.0, 1e4, "um"))
      ->capture_default_str();
  sub->add_option("--noise-um", args->options.noise_um, "centre noise per coordinate (um)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--validation-placements", args->options.validation_placements, "number of validation placements")
      ->check(Count(0, 1000))
      ->capture_default_str();
  sub->add_option("--pitch-error-um", args->options.pitch_error_um, "calotte deviations of the uncalibrated bar (um)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--hidden-effect", args->options.hidden_effect,
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
  sub->add_option("--effect-size", args->options.effect_size,
                  "size of the hidden effect; 0 = default: thermal_drift 3 um/min, higher_order 80 um, reference_anchor "
                  "30 mm, z_coupling 500 urad (X; Y half), outliers 80 um, scale 300 ppm")
      ->check(Within(0.0, 1e5))
      ->capture_default_str();
  sub->add_option("--drift-tau-min", args->options.drift_tau_min,
                  "thermal_drift: 0 drifts linearly in t; > 0 a warm-up B (1 - exp(-t/tau)) with this time constant (min)")
      ->check(Within(0.0, 1e4, "min"))
      ->capture_default_str();
  sub->add_option("--periodic-um", args->options.periodic_um,
                  "a lead screw's cyclic error along X and Y that no polynomial model takes (um; 0: none)")
      ->check(Within(0.0, 1e3, "um"))
      ->capture_default_str();
  sub->add_option("--period-mm", args->options.period_mm, "its period")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--height-step-mm", args->options.height_step_mm,
                  "the bar lies on a wedge rising by -step, 0, +step over its length, placement by placement")
      ->check(Within(-100.0, 100.0, "mm"))
      ->capture_default_str();
  sub->add_flag("--serpentine", args->options.serpentine,
                "measure every other placement from its last calotte back to its first, so that a drift shows at the "
                "shared start (on a wedge, drift and pitch and roll are otherwise confounded)");
  sub->add_flag("--different-starts", args->different_starts,
                "identification placements do not share their first calotte's spot (needs --anchor first-tile)");
  sub->add_option("--stitched-frame", args->stitched_frame,
                  "rotated: each stitched export keeps the orientation of its first tile, turned with the stage there, "
                  "as an instrument that registers tiles by translation does (default); translated: the turn left out")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  sub->add_option("--surfaces", args->surfaces,
                  "write each export as a height map of this format instead of a centre CSV (the bar's calottes where "
                  "the export places them, with height noise), the centre exports of the same simulation in "
                  "OUTPUT/centres; 'fvm calibrate OUTPUT' then searches the surfaces, e.g. --surfaces x3p")
      ->check(CLI::IsMember({"x3p", "tif"}));
  sub->add_option("--surface-pixel-mm", args->surface.pixel_mm,
                  "with --surfaces: pixel size of the surfaces (coarse: a 160 mm bar at 45 degrees is 2300 x 2300 "
                  "points at 0.05 mm), e.g. --surface-pixel-mm 0.1")
      ->check(Within(0.02, 0.5, "mm"))  // finer: a bar's mosaic of billions of points; coarser: no calotte left
      ->capture_default_str();
  sub->add_option("--surface-noise-um", args->surface.noise_um, "with --surfaces: height noise per pixel (um)")
      ->check(Within(0.0, 100.0, "um"))
      ->capture_default_str();
  sub->footer("Example:\n  fvm simulate fvm-batch -o batch --seed 7 --noise-um 0.5\n"
              "  fvm simulate fvm-batch -o raw --seed 7 --surfaces x3p && fvm calibrate raw --model 27");
  sub->callback([args] { Run(*args); });
  RegisterSimulateTracker(simulate);
  RegisterSimulateScan(simulate);
  RegisterSimulateTestPiece(simulate);
}

}  // namespace fvm::cli
