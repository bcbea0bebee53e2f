#pragma once
// `fvm simulate fvm-batch -o DIR`: a synthetic calibration batch (17-calotte bar placements on the FVM stage,
// stitched and stitching-free exports) with the stage error model it was made with recorded in DIR/truth.json;
// optionally the exports as raw height maps (x3p, tif) with the centre exports in DIR/centres.

#include <filesystem>
#include <string>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/raw_export_simulation.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// The options as `fvm simulate fvm-batch` spells them.
struct SimulateBatchOptions {
  artefacts::FvmBatchOptions batch;     // --seed, --truth-model, --noise-um, ... (same_start and stitched_frame
                                        // come from the two fields below)
  bool different_starts = false;        // identification placements do not share their first calotte's spot
  std::string stitched_frame = "rotated";  // or "translated"
  std::string surfaces;                 // "x3p" or "tif": raw exports instead of centre CSVs; empty: CSVs
  artefacts::RawExportSimulationOptions surface;  // --surface-pixel-mm, --surface-noise-um (its seed: --seed)

  // Throws InputError naming the option (--hidden-effect, --stitched-frame, --surfaces, ...).
  void Check() const;
};

struct SimulatedBatch {
  std::filesystem::path dir;
  SimulateBatchOptions options;         // as run (same_start, stitched frame and surface seed resolved)
  artefacts::SimulatedFvmBatch simulation;
};

// Simulates and writes the batch into `dir` (created), truth.json last.
SimulatedBatch SimulateBatch(const SimulateBatchOptions& options, const std::filesystem::path& dir);

// The truth.json document as the JSON, and the lines the command prints.
Summary Summarize(const SimulatedBatch& batch);

}  // namespace fvm::workflows
