#include "workflows/calibrate.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/dense_decomposition.h"
#include "artefacts/batch_observations.h"
#include "core/input_error.h"
#include "stage/calibration.h"
#include "stage/parameter_layout.h"

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
// box the scans cover (at the first tile's height), um, less the rigid motion in xy (an offset and a turn about z)
// that no registered image can tell: the result's frame fixes it by convention (the first tile's), and any
// comparison with another calibration or a truth removes it. It is what the coefficients' covariance says of the
// error field once that motion is projected out of the field's Jacobian.
double PredictedXyUm(const stage::Calibration& calibration, const std::vector<artefacts::RegisteredScan>& scans) {
  Eigen::Vector3d lo = scans.front().encoder_mm.front(), hi = lo;
  for (const auto& scan : scans) {
    for (const Eigen::Vector3d& e : scan.encoder_mm) lo = lo.cwiseMin(e), hi = hi.cwiseMax(e);
  }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  constexpr int kSide = 11, kPoints = kSide * kSide;
  const auto n = static_cast<Eigen::Index>(calibration.values.size());
  if (n == 0 || calibration.covariance.rows() != n) return 0.0;
  Eigen::MatrixXd field(2 * kPoints, n), rigid(2 * kPoints, 3);
  for (int i = 0; i < kPoints; ++i) {
    const Eigen::Vector3d q(lo.x() + (hi.x() - lo.x()) * (i % kSide) / (kSide - 1.0),
                            lo.y() + (hi.y() - lo.y()) * (i / kSide) / (kSide - 1.0), scans.front().encoder_mm.front().z());
    field.middleRows(2 * i, 2) = stage::ForwardJacobian(calibration.layout, calibration.values.data(), q).topRows(2);
    rigid.row(2 * i) << 1.0, 0.0, -(q.y() - centre.y());  // a small turn w about z moves (x, y) by w (-y, x)
    rigid.row(2 * i + 1) << 0.0, 1.0, q.x() - centre.x();
  }
  const Eigen::MatrixXd basis =
      Decompose<Eigen::HouseholderQR<Eigen::MatrixXd>>(rigid, "the rigid motions of the scanned field").householderQ() *
      Eigen::MatrixXd::Identity(2 * kPoints, 3);
  const Eigen::MatrixXd seen = field - basis * (basis.transpose() * field);
  return std::sqrt(std::max(0.0, (seen * calibration.covariance * seen.transpose()).trace()) / kPoints) * 1e3;
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
  ScanCalibrationResult r{identify(options.pixel_u_mm), 0.0, 0.0, 0.0, 0.0, {}, {}, {}};
  const stage::Calibration& cal = r.fitted.result.calibration;
  r.predicted_without_pixel_um = options.pixel_u_mm > 0.0 ? PredictedXyUm(identify(0.0).result.calibration, scans) : 0.0;
  r.predicted_xy_um = PredictedXyUm(cal, scans);
  r.predicted_xy_with_misfit_um = std::hypot(r.predicted_xy_um, r.fitted.split.misfit_mm * 1e3);
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
