#pragma once
// Synthetic calibration batches for the focus-variation microscope stage, with a recorded truth: the published
// procedure ([Pérez 2019] sections 2.2-3) played on a known stage error model.
//
// The 17-calotte bar is placed on a 200 x 200 mm stage along X, along Y and obliquely with its first calotte at
// one physical spot (identification), and at random positions and angles over the whole stage (validation).
// Each placement is "measured" twice: stitching-free centres q carry the stage error (F(q) = true position), and
// stitched centres carry only the error of the measurement's first tile a, in its frame (stage/stitched_frame.h):
// s = a + T (F(q) - F(a)), turned with the stage at a (T = C(a)^-1) or, translated, T = I.

#include <string>
#include <string_view>
#include <vector>

#include "artefacts/io/batch.h"
#include "stage/parameter_layout.h"
#include "stage/stitched_frame.h"

namespace fvm::artefacts {

struct FvmBatchOptions {
  unsigned seed = 1;
  std::string truth_model = "27";      // a layout name of stage::FvmModelLayout
  std::string truth_terms;             // or a model of one's own (stage::ComposeLayout), which then replaces it
  double mean_error_um = 125.0;        // mean stage error over the stage (paper: 141 um before compensation)
  double noise_um = 0.5;               // centre noise per coordinate, in both measurements
  int validation_placements = 10;      // 17 centres each (paper: 162 validation centres)
  bool same_start = true;              // identification placements share their first calotte's spot
  double pitch_error_um = 5.0;         // the bar is uncalibrated: its calottes deviate from 10 mm pitch
  double seconds_per_centre = 20.0;    // measurement time per calotte (the t column)
  // Every other placement is measured from its last calotte back to its first. Along a bar, a drift and anything
  // that grows along it (a height on a wedge, a scale) both grow with the index; measuring back makes the drift
  // show at the shared start spot, where the other effects do not.
  bool serpentine = false;
  // A lead screw's cyclic error along X and Y that no polynomial model takes (stage_truth.h); 0: none.
  double periodic_um = 0.0, period_mm = 25.0;
  double height_step_mm = 0.0;         // the bar lies on a wedge: it rises by -step, 0, +step over its length, in turn
  // Rotated by default: the instrument registers tiles by translation only, so its mosaic keeps the orientation of
  // the first tile, turned with the stage there. Translated leaves the turn out (the convention before).
  stage::StitchedFrame stitched_frame = stage::StitchedFrame::kRotated;

  // Effects the stage model does not describe, hidden in the data for the discrepancy workflow (fvm diagnose):
  // one name from the contract list, or several joined by commas ("thermal_drift,scale"). `effect_size` 0 takes
  // each one's default in parentheses (another value applies to each):
  //   thermal_drift   stitching-free centres drift with measurement time (3 um/min, mostly along x)
  //   higher_order    the truth gets the next polynomial order of xTx (80 um at the end of the travel)
  //   reference_anchor identification placements start apart: each is anchored at its own first tile (30 mm)
  //   z_coupling      pitch and roll of X (500 urad each) and of Y (half that); use with height_step_mm
  //   outliers        three failed sphere fits among the identification centres (80 um)
  //   scale           stitched distances scaled about the first tile, a lens scale error (300 ppm)
  std::string hidden_effect;
  double effect_size = 0.0;
  // thermal_drift: 0 drifts linearly in t; > 0 is a warm-up B (1 - exp(-t/tau)) with this time constant (min) and
  // the same initial rate ([Pérez thesis] eqs. 5.1-5.2).
  double drift_tau_min = 0.0;
  bool Hides(std::string_view effect) const;  // `effect` is one of hidden_effect's names
  void Check() const;                  // throws std::invalid_argument
};

// The effect names SimulateFvmBatch can hide.
std::vector<std::string> HiddenEffectNames();

struct FvmBatchTruth {
  stage::ParameterLayout layout;
  std::vector<double> values;          // free coefficients of layout, mm and rad
  double mean_error_um = 0.0;          // achieved mean |F(q) - q| over a stage grid
  double max_error_um = 0.0;
};

struct SimulatedFvmBatch {
  Batch batch;
  FvmBatchTruth truth;
  // The same placements without centre noise (and without the hidden outliers, failed fits of centre exports):
  // where the calottes of each export really are, for rendering the exports' surfaces (raw_export_simulation.h).
  Batch exact = {};
};

SimulatedFvmBatch SimulateFvmBatch(const FvmBatchOptions& options);

}  // namespace fvm::artefacts
