#pragma once
// The main job: identify the stage model from a batch of stitched / stitching-free pairs of an uncalibrated
// artefact ([Pérez 2019]), or from the registrations of stitched calibration scans of any textured part, and judge
// it on held-out measurements.

#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "artefacts/scan_observations.h"
#include "stage/identification.h"
#include "stage/validation.h"
#include "workflows/model_choice.h"

namespace fvm::workflows {

// A calibration (or none) judged on measurements: first what no frame changes (a rigid fit per placement, the
// distances between all pairs of centres), then each placement in its first tile's frame.
struct Judgement {
  stage::FrameFreeStats rigid, distances;
  stage::ValidationStats first_tile;
};
Judgement Judge(const stage::Calibration* calibration, const stage::MeasurementSet& set, stage::StitchedFrame frame);

// The same measurements without compensation and with the calibration.
struct BeforeAfter {
  Judgement before, after;
  std::vector<double> distance_errors_before_mm, distance_errors_after_mm;  // every pair of centres
};
BeforeAfter JudgeBeforeAfter(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                             stage::StitchedFrame frame);

struct CalibrateOptions {
  ModelChoice model;
  IdentifySettings settings;
  // Judge the identification placements when the batch holds no validation ones (what a report shows).
  bool judge_identification = false;
};

struct BatchCalibration {
  stage::IdentificationResult result;
  stage::MeasurementSet identification;
  stage::ValidationStats identification_before;   // the identification placements without compensation
  std::optional<stage::MeasurementSet> validation;  // the batch's validation placements, if it names any
  // On the validation placements; without them, on the identification ones when asked (judge_identification).
  std::optional<BeforeAfter> judged;
  const stage::MeasurementSet& Shown() const { return validation ? *validation : identification; }
};

// Throws InputError naming the model when the batch cannot carry it.
BatchCalibration CalibrateBatch(const artefacts::Batch& batch, const CalibrateOptions& options);

struct ScanCalibrateOptions {
  ModelChoice model;
  IdentifySettings settings;
  double pixel_mm = 0.0;    // the pixel size on the part: the scale of every registered offset
  double pixel_u_mm = 0.0;  // its standard uncertainty, propagated
};

struct ScanCalibrationResult {
  artefacts::ScanCalibration fitted;
  // The standard uncertainty (k = 1) of the xy stage error, rms over the box the scans cover less the offset and
  // the turn about z no registered image can tell (um): from the coefficients' covariance, the same without the
  // pixel size's share (0 when pixel_u_mm is 0), and what treating the chained positions as independent points of
  // equal weight would have predicted.
  double predicted_xy_um = 0.0, predicted_without_pixel_um = 0.0, predicted_independent_um = 0.0;
  // The figure `fvm calibrate --scan` prints: predicted_xy_um and the misfit along the scans (fitted.split.misfit_mm)
  // in quadrature (um).
  double predicted_xy_with_misfit_um = 0.0;
  std::vector<std::string> validation_placements;
  std::optional<stage::MeasurementSet> validation;
  std::optional<BeforeAfter> judged;  // on the validation placements
};

// `validate`: an artefact batch of the same stage whose validation placements (all of them, without batch.json)
// judge the result. Throws InputError when no pair of any scan registered, or the model cannot be carried.
ScanCalibrationResult CalibrateScans(const std::vector<artefacts::RegisteredScan>& scans,
                                     const ScanCalibrateOptions& options, const artefacts::Batch* validate = nullptr);

}  // namespace fvm::workflows
