#include "workflows/calibrate.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "artefacts/batch_observations.h"
#include "core/input_error.h"
#include "stage/calibration.h"

namespace fvm::workflows {

Judgement Judge(const stage::Calibration* calibration, const stage::MeasurementSet& set, stage::StitchedFrame frame) {
  stage::ValidationStats first_tile = stage::Validate(calibration, set.observations, set.anchors, frame);
  if (calibration != nullptr) first_tile.undetermined_rms_mm = stage::UndeterminedRms(*calibration, set.observations, set.anchors, frame);
  return {stage::RigidValidation(calibration, set.observations), stage::PairDistanceValidation(calibration, set.observations),
          std::move(first_tile)};
}

BeforeAfter JudgeBeforeAfter(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                             stage::StitchedFrame frame) {
  return {Judge(nullptr, set, frame), Judge(&calibration, set, frame), stage::DistanceErrors(nullptr, set.observations),
          stage::DistanceErrors(&calibration, set.observations)};
}

BatchCalibration CalibrateBatch(const artefacts::Batch& batch, const CalibrateOptions& options) {
  stage::MeasurementSet identification = artefacts::Observations(batch, batch.identify);
  BatchCalibration c{IdentifyModel(options.model, identification, options.settings), std::move(identification), {}, {}, {}};
  c.identification_before = stage::Validate(nullptr, c.identification.observations, c.identification.anchors);
  if (!batch.validate.empty()) c.validation = artefacts::Observations(batch, batch.validate);
  if (c.validation || options.judge_identification) {
    c.judged = JudgeBeforeAfter(c.result.calibration, c.Shown(), options.settings.Frame());
  }
  return c;
}

namespace {

// The standard uncertainty (k = 1) of the xy stage error a calibration predicts, rms over an 11 x 11 grid of the
// box the scans cover, um: the figure that compares weightings and the pixel size's share.
double PredictedXyUm(const stage::Calibration& calibration, const std::vector<artefacts::RegisteredScan>& scans) {
  Eigen::Vector3d lo = scans.front().encoder_mm.front(), hi = lo;
  for (const auto& scan : scans) {
    for (const Eigen::Vector3d& e : scan.encoder_mm) lo = lo.cwiseMin(e), hi = hi.cwiseMax(e);
  }
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j) {
      const Eigen::Vector3d q(lo.x() + (hi.x() - lo.x()) * i / 10.0, lo.y() + (hi.y() - lo.y()) * j / 10.0, lo.z());
      const Eigen::Matrix3d c = stage::Correct(calibration, q).covariance;
      sum += c(0, 0) + c(1, 1);
      ++count;
    }
  }
  return std::sqrt(sum / count) * 1e3;
}

}  // namespace

ScanCalibrationResult CalibrateScans(const std::vector<artefacts::RegisteredScan>& scans,
                                     const ScanCalibrateOptions& options, const artefacts::Batch* validate) {
  bool any = false;
  for (const auto& scan : scans) {
    for (const auto& pair : scan.registration.pairs) any = any || pair.accepted;
  }
  if (!any) {
    throw InputError("no pair of neighbouring tiles registered in any scan (first: " +
                     scans.front().registration.pairs.front().rejection +
                     "): the tiles need a texture that registers, and encoder readings of their centres");
  }
  const stage::ParameterLayout layout = options.model.Layout();
  // Without the pixel size's share first, to say how much it adds.
  const auto identify = [&](double pixel_u_mm) {
    try {
      artefacts::ScanCalibration c = artefacts::IdentifyFromScans(layout, scans, options.pixel_mm, pixel_u_mm,
                                                                  options.settings.ToOptions(stage::MeasurementSet{}));
      c.result.calibration.model = options.model.Name();
      return c;
    } catch (const std::invalid_argument& e) {
      throw InputError("model " + options.model.Name() + ": " + e.what());
    }
  };
  ScanCalibrationResult r{identify(options.pixel_u_mm), 0.0, 0.0, 0.0, {}, {}, {}};
  const stage::Calibration& cal = r.fitted.result.calibration;
  r.predicted_without_pixel_um = options.pixel_u_mm > 0.0 ? PredictedXyUm(identify(0.0).result.calibration, scans) : 0.0;
  r.predicted_xy_um = PredictedXyUm(cal, scans);
  // What treating the chained positions as independent points of equal weight would have predicted.
  const stage::MeasurementSet positions = artefacts::ScanPositions(scans, options.pixel_mm);
  stage::IdentificationOptions chained_options = options.settings.ToOptions(positions);
  chained_options.anchor = stage::Anchor::kFirstTile;
  r.predicted_independent_um = PredictedXyUm(stage::Identify(layout, positions.observations, chained_options).calibration, scans);
  if (validate) {
    r.validation_placements = validate->validate;
    if (r.validation_placements.empty()) {
      for (const auto& p : validate->placements) r.validation_placements.push_back(p.name);
    }
    r.validation = artefacts::Observations(*validate, r.validation_placements);
    r.judged = JudgeBeforeAfter(cal, *r.validation, options.settings.Frame());
  }
  return r;
}

}  // namespace fvm::workflows
