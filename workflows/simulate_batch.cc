#include "workflows/simulate_batch.h"

#include <fmt/core.h>

#include <stdexcept>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/surface_file.h"
#include "stage/fvm_stage_models.h"
#include "workflows/model_choice.h"

namespace fvm::workflows {
namespace {

// The surfaces of every placement as FORMAT files in `dir`, the roles beside them, the centre exports of the same
// simulation (the CSV route) in dir/centres.
void WriteRawExports(const std::filesystem::path& dir, const SimulateBatchOptions& o,
                     const artefacts::SimulatedFvmBatch& sim) {
  artefacts::WriteBatch(dir / "centres", sim.batch);
  artefacts::Batch roles = sim.batch;
  roles.placements.clear();
  artefacts::WriteBatch(dir, roles);  // batch.json alone
  for (std::size_t i = 0; i < sim.exact.placements.size(); ++i) {
    const artefacts::Placement& p = sim.exact.placements[i];
    const artefacts::RawExportPair maps = artefacts::RenderRawExports(p, i, o.surface);
    imaging::WriteHeightMap(dir / (p.name + ".stitched." + o.surfaces), maps.stitched);
    imaging::WriteHeightMap(dir / (p.name + ".free." + o.surfaces), maps.free);
  }
}

std::string TruthModelName(const artefacts::FvmBatchOptions& o) { return ModelChoice{o.truth_model, o.truth_terms}.Name(); }

// truth.json: the options that shaped the batch and the stage's coefficients (sorted keys, as always written).
nlohmann::json TruthDocument(const SimulatedBatch& b) {
  const artefacts::FvmBatchOptions& o = b.options.batch;
  const artefacts::FvmBatchTruth& t = b.simulation.truth;
  nlohmann::json truth;
  truth["what"] = "stage error model the batch was simulated with (fvm simulate fvm-batch)";
  truth["model"] = TruthModelName(o);
  truth["seed"] = o.seed;
  truth["noise_um"] = o.noise_um;
  truth["pitch_error_um"] = o.pitch_error_um;
  truth["same_start"] = o.same_start;
  truth["height_step_mm"] = o.height_step_mm;
  truth["serpentine"] = o.serpentine;
  truth["periodic_um"] = o.periodic_um;
  truth["period_mm"] = o.period_mm;
  truth["stitched_frame"] = b.options.stitched_frame;
  if (!b.options.surfaces.empty()) {
    truth["surfaces"] = {{"format", b.options.surfaces}, {"pixel_mm", b.options.surface.pixel_mm},
                         {"height_noise_um", b.options.surface.noise_um}, {"centres", "centres/"}};
  }
  truth["hidden_effect"] = o.hidden_effect.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.hidden_effect);
  truth["effect_size"] = o.effect_size;
  truth["drift_tau_min"] = o.drift_tau_min;
  truth["mean_error_um"] = t.mean_error_um;
  truth["max_error_um"] = t.max_error_um;
  const std::vector<std::string> names = t.layout.FreeNames();
  for (size_t i = 0; i < names.size(); ++i) {
    const auto& c = t.layout.coefficients()[static_cast<size_t>(t.layout.FindCoefficient(names[i]))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    truth["parameters"].push_back(
        {{"name", names[i]}, {"value", t.values[i]}, {std::string("value_") + unit.name, t.values[i] * unit.per_si}});
  }
  return truth;
}

}  // namespace

void SimulateBatchOptions::Check() const {
  try {
    batch.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  if (stitched_frame != "rotated" && stitched_frame != "translated") {
    throw InputError("--stitched-frame '" + stitched_frame + "': use rotated or translated");
  }
  if (!surfaces.empty() && surfaces != "x3p" && surfaces != "tif") {
    throw InputError("--surfaces '" + surfaces + "': use x3p or tif");
  }
  try {
    surface.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
}

SimulatedBatch SimulateBatch(const SimulateBatchOptions& options, const std::filesystem::path& dir) {
  options.Check();
  SimulateBatchOptions run = options;
  run.batch.same_start = !options.different_starts;
  run.batch.stitched_frame = stage::ParseStitchedFrame(options.stitched_frame);
  run.surface.seed = options.batch.seed;
  SimulatedBatch b{dir, run, artefacts::SimulateFvmBatch(run.batch)};
  if (options.surfaces.empty()) {
    artefacts::WriteBatch(dir, b.simulation.batch);
  } else {
    WriteRawExports(dir, b.options, b.simulation);
  }
  WriteFileAtomically(dir / "truth.json", TruthDocument(b).dump(2) + "\n");
  return b;
}

Summary Summarize(const SimulatedBatch& b) {
  const artefacts::FvmBatchOptions& o = b.options.batch;
  const artefacts::SimulatedFvmBatch& sim = b.simulation;
  Summary s;
  s.json = nlohmann::ordered_json::parse(TruthDocument(b).dump());  // the file's keys in the file's order
  size_t centres = 0;
  for (const auto& p : sim.batch.placements) centres += p.ids.size();
  s.text = fmt::format(
      "simulated {} placements ({} centres) into {}: truth model {}, mean stage error {:.1f} um (max {:.1f} um), "
      "noise {} um, seed {}\n",
      sim.batch.placements.size(), centres, b.dir.string(), TruthModelName(o), sim.truth.mean_error_um,
      sim.truth.max_error_um, o.noise_um, o.seed);
  if (!b.options.surfaces.empty()) {
    s.text += fmt::format(
        "surfaces: {} per placement, stitched and stitching-free ({} um pixel, {} um height noise); the centre "
        "exports of the same simulation in {}/centres\n",
        b.options.surfaces, b.options.surface.pixel_mm * 1e3, b.options.surface.noise_um, b.dir.string());
  }
  return s;
}

}  // namespace fvm::workflows
