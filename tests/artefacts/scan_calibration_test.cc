// Calibration from stitched scans of a textured part (issue 21): tiles rendered where a stage with known errors puts
// every pixel (artefacts/simulation/scan_simulation.h), registered as chains, identified from the displacements
// between neighbours. The truth carries a lead screw's cycle (0.3 um) that no polynomial model takes.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "artefacts/scan_correlated_errors.h"
#include "artefacts/scan_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "stage/calibration.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "stage/parameter_layout.h"

namespace fvm::artefacts {
namespace {

constexpr double kFov5xMm = 2.82;  // [Pérez thesis] Table 5.2: the 5x lens' field of view

StageTruth PublishedSizeStage(unsigned seed) {
  FvmBatchOptions batch;
  batch.seed = seed;
  batch.validation_placements = 0;
  const FvmBatchTruth t = SimulateFvmBatch(batch).truth;  // 125 um mean error, guideways turning tens of urad
  return StageTruth{t.layout, t.values, 0.3, 25.0};
}

struct Scanned {
  std::vector<RegisteredScan> scans;
  double pixel_mm = 0.0;
};

// A row, a column and a diagonal of 150 mm at each height, 5x lens, 25 % overlap, ground texture.
Scanned ScanAndRegister(const StageTruth& truth, const std::vector<double>& heights, int tile_px, bool height_maps = false) {
  imaging::CalibrationScanOptions plan;
  plan.heights_mm = heights;
  imaging::TilePlanOptions lens;
  lens.fov_mm = kFov5xMm;
  lens.overlap = 0.25;
  ScanSimulationOptions options;
  options.tile_px = tile_px;
  options.pixel_mm = kFov5xMm / tile_px;
  options.camera = ScanTexture("ground");
  options.heights = height_maps;
  Scanned out;
  out.pixel_mm = options.pixel_mm;
  for (const SimulatedScan& scan : SimulateScans(truth, imaging::PlanCalibrationScans(plan, lens), options)) {
    out.scans.push_back(RegisterScan(scan.name, scan.encoder_mm, scan.images, options.pixel_mm, height_maps));
  }
  return out;
}

stage::IdentificationOptions RotatedFrame() {
  stage::IdentificationOptions options;
  options.frame = stage::StitchedFrame::kRotated;
  return options;
}

// The xy stage error a calibration predicts against the truth's at 200 positions over the scanned square, once the
// rigid motion in xy (offset, turn about z) that no image can tell is removed, by a least-squares fit written here.
struct XyComparison {
  double rms_um = 0, max_um = 0;
};
XyComparison CompareInXy(const stage::Calibration& cal, const StageTruth& truth, double z) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> coordinate(-170.0, -30.0);
  Eigen::MatrixXd a(400, 3);
  Eigen::VectorXd b(400);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d q(coordinate(random), coordinate(random), z);
    a.row(2 * i) << 1, 0, -q.y();
    a.row(2 * i + 1) << 0, 1, q.x();
    b.segment<2>(2 * i) = (truth.Forward(q) - stage::Forward(cal.layout, cal.values, q)).head<2>();
  }
  const Eigen::VectorXd r = b - a * a.colPivHouseholderQr().solve(b);
  XyComparison out;
  for (int i = 0; i < 200; ++i) {
    const double e = r.segment<2>(2 * i).norm() * 1e3;
    out.rms_um += e * e / 200.0;
    out.max_um = std::max(out.max_um, e);
  }
  out.rms_um = std::sqrt(out.rms_um);
  return out;
}

// Registration against the geometry written out here: b's offset in a's pixels is the part's displacement seen by
// the camera, (C_a^-1 + C_b^-1) / 2 (F(b) - F(a)), and the stage's turn of tens of urad over a 2 mm step (0.1 um)
// is seen: leaving it out fits worse.
TEST(ScanCalibration, RegisteredOffsetsAreTheDisplacementsTurnedWithTheCamera) {
  const StageTruth truth = PublishedSizeStage(1);
  const Scanned s = ScanAndRegister(truth, {-50.0}, 192);
  double turned = 0, unturned = 0;
  int n = 0;
  for (const RegisteredScan& scan : s.scans) {
    for (const imaging::PairRegistration& p : scan.registration.pairs) {
      ASSERT_TRUE(p.accepted) << scan.name << " " << p.a << ": " << p.rejection;
      const Eigen::Vector3d a = scan.encoder_mm[static_cast<size_t>(p.a)], b = scan.encoder_mm[static_cast<size_t>(p.b)];
      const Eigen::Vector3d move = truth.Forward(b) - truth.Forward(a);
      const Eigen::Vector3d seen = 0.5 * (truth.Camera(a).inverse() + truth.Camera(b).inverse()) * move;
      const Eigen::Vector2d measured(p.offset_px.x() * s.pixel_mm, -p.offset_px.y() * s.pixel_mm);
      turned += (measured - seen.head<2>()).squaredNorm();
      unturned += (measured - move.head<2>()).squaredNorm();
      ++n;
    }
  }
  const double turned_um = std::sqrt(turned / n) * 1e3, unturned_um = std::sqrt(unturned / n) * 1e3;
  // Registration of these 192 px tiles (14.7 um pixels) is good to about 0.005 px: 0.07 um.
  EXPECT_LT(turned_um, 0.1);
  EXPECT_LT(turned_um, 0.7 * unturned_um) << "unturned " << unturned_um << " um";
}

// The target of issue 21 at a test's size (384 px tiles: 7.3 um pixels, where 1024 px have 2.75 um): the stage error in xy within 1 um rms and 2 um max (the published 2-D
// method: 3 um max over 100 mm) where the chained positions, fitted as independent points, leave more; and the
// prediction (coefficients from the white part of the residuals, plus the misfit along the scans) not below 0.8 of
// what is seen.
TEST(ScanCalibration, DisplacementsBetweenNeighboursRecoverTheStageInXY) {
  const StageTruth truth = PublishedSizeStage(1);
  const Scanned s = ScanAndRegister(truth, {-50.0}, 384);
  const ScanCalibration fit = IdentifyFromScans(stage::FvmModelLayout("27"), s.scans, s.pixel_mm, 0.0, RotatedFrame());
  const XyComparison turned = CompareInXy(fit.result.calibration, truth, -50.0);

  stage::IdentificationOptions chained_options = RotatedFrame();
  chained_options.anchor = stage::Anchor::kFirstTile;
  const stage::MeasurementSet positions = ScanPositions(s.scans, s.pixel_mm);
  chained_options.anchors = positions.anchors;
  const stage::IdentificationResult chained = stage::Identify(stage::FvmModelLayout("27"), positions.observations, chained_options);
  const XyComparison independent = CompareInXy(chained.calibration, truth, -50.0);

  EXPECT_LT(turned.rms_um, 1.0);
  EXPECT_LT(turned.max_um, 2.0);
  EXPECT_LT(turned.rms_um, independent.rms_um);
  double u2 = 0;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Matrix3d c = stage::Correct(fit.result.calibration, Eigen::Vector3d(-170 + 14 * (i % 10), -170 + 14 * (i / 10), -50)).covariance;
    u2 += (c(0, 0) + c(1, 1)) / 100.0;
  }
  const double predicted_um = std::hypot(std::sqrt(u2) * 1e3, fit.split.misfit_mm * 1e3);
  EXPECT_GT(predicted_um, 0.8 * turned.rms_um);
  EXPECT_LT(predicted_um, 5.0 * turned.rms_um) << "a prediction this large says little";
  // The cycle of 0.3 um the model cannot take shows as misfit along the scans, of its size.
  EXPECT_GT(fit.split.misfit_mm * 1e3, 0.1);
  EXPECT_LT(fit.split.misfit_mm * 1e3, 0.4);
}

// The field distortion's share (issue 43): a field error that moves every displacement as the coefficients `a` would
// (S_i = J_i a, one field term of variance s^2) moves every predicted displacement by exactly J_i a, with that
// variance; whatever part of `a` the displacements cannot see (aliases) it leaves out, and nothing else.
TEST(ScanCalibration, FieldDistortionErrorMovesTheCoefficientsAsItMovesTheDisplacements) {
  const stage::ParameterLayout layout = stage::FvmModelLayout("27");
  const stage::Calibration cal{"27", layout, std::vector<double>(static_cast<size_t>(layout.NumFree()), 0.0), {}, 0.0,
                               std::nullopt, {}};
  stage::MeasurementSet set;
  for (int k = 0; k < 12; ++k) {  // a row and a column of 2 mm steps
    for (const Eigen::Vector3d& step : {Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, -2, 0)}) {
      stage::Observation o;
      o.from = Eigen::Vector3d(-120, -80, -50) + k * step;
      o.command = *o.from + step;
      o.covariance = Eigen::Vector3d(1e-8, 1e-8, std::numeric_limits<double>::infinity()).asDiagonal();
      set.observations.push_back(o);
    }
  }
  Eigen::VectorXd a = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(cal.values.size()));
  a(0) = 1e-4, a(a.size() - 1) = -2e-5, a(a.size() / 2) = 3e-6;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> sensitivity;
  std::vector<Eigen::Vector3d> moved;
  for (const stage::Observation& o : set.observations) {
    const Eigen::MatrixXd j = stage::ForwardJacobian(cal.layout, cal.values.data(), o.command) -
                              stage::ForwardJacobian(cal.layout, cal.values.data(), *o.from);
    moved.push_back(j * a);
    moved.back().z() = 0.0;  // grey tiles: z unobserved
    sensitivity.push_back(moved.back());
  }
  const double s = 0.01;  // px
  const Eigen::MatrixXd covariance = FieldDistortionCovariance(cal, set, sensitivity, Eigen::MatrixXd::Constant(1, 1, s * s));
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const stage::Observation& o = set.observations[i];
    const Eigen::MatrixXd j = (stage::ForwardJacobian(cal.layout, cal.values.data(), o.command) -
                               stage::ForwardJacobian(cal.layout, cal.values.data(), *o.from)).topRows(2);
    const Eigen::Matrix2d predicted = j * covariance * j.transpose();
    const Eigen::Matrix2d expected = s * s * moved[i].head<2>() * moved[i].head<2>().transpose();
    EXPECT_LT((predicted - expected).norm(), 1e-9 * expected.norm() + 1e-30) << i;
  }
  EXPECT_GT(covariance.norm(), 0.0);
}

bool Fixed(const stage::IdentificationResult& r, const std::string& name);

// Height-map tiles: the overlap of two registered tiles shows how far the stage rose between them, so the scans
// calibrate z too (the straightness xTz, yTz); grey tiles leave it at 0. Judged against the truth's z at 200
// positions once the plane no displacement can tell (offset, tilt) is removed, by a fit written here.
TEST(ScanCalibration, HeightMapTilesCalibrateZ) {
  const StageTruth truth = PublishedSizeStage(1);
  const Scanned s = ScanAndRegister(truth, {-50.0}, 192, /*height_maps=*/true);
  const ScanCalibration fit = IdentifyFromScans(stage::FvmModelLayout("27"), s.scans, s.pixel_mm, 0.0, RotatedFrame());
  const auto z_error_um = [&](const stage::Calibration* cal) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> coordinate(-170.0, -30.0);
    Eigen::MatrixXd a(200, 3);
    Eigen::VectorXd b(200);
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d q(coordinate(random), coordinate(random), -50.0);
      a.row(i) << 1, q.x(), q.y();
      b(i) = truth.Forward(q).z() - (cal ? stage::Forward(cal->layout, cal->values, q).z() : q.z());
    }
    return (b - a * a.colPivHouseholderQr().solve(b)).norm() / std::sqrt(200.0) * 1e3;
  };
  const double before = z_error_um(nullptr), after = z_error_um(&fit.result.calibration);
  // The covariance carries what the pairs of a scan share (scan_correlated_errors.h) through the z steps too.
  EXPECT_TRUE(fit.result.calibration.covariance.allFinite());
  EXPECT_GT(before, 3.0);  // the stage's z error beyond a plane: 5 um rms on seed 1
  EXPECT_LT(after, 1.0) << "before " << before;
  // The 27 model carries the axes' linear z straightness in the squareness terms (xTz1 and yTz1 are dropped: they
  // are xWz0 and yWz0); the overlaps determine them. (The constants xTz0, yTz0 move every tile alike: no
  // displacement shows them.)
  for (const char* name : {"xWz0", "xWz1", "yWz0", "yWz1"}) {
    EXPECT_GE(fit.result.calibration.layout.FreeIndexOf(name), 0) << name << " is not a free coefficient of the fit";
    EXPECT_FALSE(Fixed(fit.result, name)) << name;
  }
}

bool Fixed(const stage::IdentificationResult& r, const std::string& name) {
  return std::any_of(r.fixed.begin(), r.fixed.end(), [&](const stage::FixedCoefficient& f) { return f.name == name; });
}

// A scan at one height cannot tell pitch and roll from positioning and squareness (their Abbe arm is the same
// everywhere); scans at two heights can. The pixel size sets the scale of xTx1 and yTy1: its uncertainty widens them.
TEST(ScanCalibration, ASecondHeightMakesPitchAndRollIdentifiable) {
  const StageTruth truth = PublishedSizeStage(2);
  const Scanned one = ScanAndRegister(truth, {-50.0}, 128);
  const Scanned two = ScanAndRegister(truth, {-50.0, -40.0}, 128);
  const stage::ParameterLayout layout = stage::FvmModelLayout("27");
  const ScanCalibration flat = IdentifyFromScans(layout, one.scans, one.pixel_mm, 0.0, RotatedFrame());
  const ScanCalibration stepped = IdentifyFromScans(layout, two.scans, two.pixel_mm, 0.0, RotatedFrame());
  for (const char* name : {"xRy1", "yRx1"}) {
    EXPECT_TRUE(Fixed(flat.result, name)) << name;
    EXPECT_FALSE(Fixed(stepped.result, name)) << name;
  }
  // 10 ppm of pixel size: 1.5 um over 150 mm, on xTx1 (plausible size over the half travel of 100 mm).
  const ScanCalibration scaled = IdentifyFromScans(layout, one.scans, one.pixel_mm, 1e-5 * one.pixel_mm, RotatedFrame());
  const int slot = flat.result.calibration.layout.FreeIndexOf("xTx1");
  const double u0 = std::sqrt(flat.result.calibration.covariance(slot, slot));
  const double u1 = std::sqrt(scaled.result.calibration.covariance(slot, slot));
  const double expected = 1e-5 * 100.0;  // 10 ppm of the 100 mm the first-order coefficient spans
  EXPECT_NEAR(std::sqrt(u1 * u1 - u0 * u0), expected, 0.1 * expected) << u0 << " " << u1;
}

// White noise as the registrations state it comes out at a white ratio of 1 and no misfit; a smooth cycle comes out
// as misfit of its own size and hardly as white noise.
TEST(ScanCalibration, ResidualsSplitIntoWhiteNoiseAndMisfit) {
  stage::MeasurementSet set;
  std::vector<Eigen::Vector3d> white, smooth;
  std::mt19937_64 random(3);
  std::normal_distribution<double> normal(0.0, 1e-4);
  for (int k = 0; k < 600; ++k) {
    stage::Observation o;
    o.from = Eigen::Vector3d(2.0 * k, 0, 0);
    o.command = Eigen::Vector3d(2.0 * (k + 1), 0, 0);
    o.covariance = Eigen::Vector3d(1e-8, 1e-8, INFINITY).asDiagonal();
    set.observations.push_back(o);
    white.emplace_back(normal(random), normal(random), 0.0);
    // A cycle of 0.3 um in position over 12 pairs: displacements of 0.3 (cos(w (k+1)) - cos(w k)) um.
    const double w = 2.0 * M_PI / 12.0;
    smooth.emplace_back(3e-4 * (std::cos(w * (k + 1)) - std::cos(w * k)), 0.0, 0.0);
  }
  const ScanResidualSplit noise = SplitScanResiduals(set, white);
  EXPECT_NEAR(noise.white_ratio, 1.0, 0.06);  // 1200 second differences
  const ScanResidualSplit cycle = SplitScanResiduals(set, smooth);
  EXPECT_NEAR(cycle.misfit_mm, 3e-4 / std::sqrt(2.0), 0.1 * 3e-4);
  EXPECT_LT(cycle.white_ratio, 0.5 * 3e-4 / 1e-4);
}

// A lead screw's cycle on each axis (X's in x along x, Y's in y along y) is seen by a row only in x and by a column
// only in y, but a point between the scans carries both (issue 43: scangen's 0.5 um screws on X and Y left the
// scan calibration's validation error 1.4 x its prediction, which pooled every scan's chained residuals into one
// axis' worth). Against the cycles' truth at 200 random points of the box (less their means over it, as a rigid
// fit removes an offset), the standardised errors per coordinate come out at rms 1: a sine sampled at 200 random
// places has a mean square within about 5 % of its own (relative sd sqrt(1/8) / (1/2) / sqrt(200)), so 0.9-1.1 is
// four standard deviations; the pooled figure gives 1.41.
TEST(ScanCalibration, MisfitAtAPointIsEachAxisSeenAlongTheScansThatMoveIt) {
  constexpr double kAmplitude = 5e-4, kPeriod = 17.0, kPitch = 1.1264, kPhaseX = 0.4, kPhaseY = 2.3;
  const auto cycle = [&](double u, double phase) { return kAmplitude * std::sin(2.0 * M_PI * u / kPeriod + phase); };
  stage::MeasurementSet set;
  std::vector<Eigen::Vector3d> residuals;
  std::mt19937_64 random(7);
  std::normal_distribution<double> noise(0.0, 5e-6);  // 5 nm of white registration noise per pair
  // Two rows (y = -100, -40) and a column (x = -100), 134 tiles each, as scangen scans.
  for (int scan = 0; scan < 3; ++scan) {
    set.groups.push_back("scan" + std::to_string(scan));
    const bool column = scan == 1;
    const auto tile = [&](int k) {  // a column runs from the highest y down
      const double along = -175.0 + kPitch * k;
      return column ? Eigen::Vector3d(-100.0, -200.0 - along, -50.0) : Eigen::Vector3d(along, scan == 0 ? -100.0 : -40.0, -50.0);
    };
    for (int k = 0; k < 133; ++k) {
      stage::Observation o;
      o.from = tile(k);
      o.command = tile(k + 1);
      o.group = scan;
      o.covariance = Eigen::Vector3d(2.5e-11, 2.5e-11, INFINITY).asDiagonal();
      set.observations.push_back(o);
      Eigen::Vector3d r(noise(random), noise(random), 0.0);
      if (column) r.y() += cycle(o.command.y(), kPhaseY) - cycle(o.from->y(), kPhaseY);
      else r.x() += cycle(o.command.x(), kPhaseX) - cycle(o.from->x(), kPhaseX);
      residuals.push_back(r);
    }
  }
  const ScanResidualSplit split = SplitScanResiduals(set, residuals);
  std::uniform_real_distribution<double> box(-175.0, -25.0);
  std::vector<Eigen::Vector2d> truth;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i = 0; i < 200; ++i) {
    truth.emplace_back(cycle(box(random), kPhaseX), cycle(box(random), kPhaseY));
    mean += truth.back() / 200.0;
  }
  Eigen::Vector2d z2 = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& t : truth) z2 += (t - mean).cwiseQuotient(split.misfit_at_point_mm).cwiseAbs2() / 200.0;
  for (int c = 0; c < 2; ++c) {
    EXPECT_GT(std::sqrt(z2[c]), 0.9) << "coordinate " << c << ": u " << split.misfit_at_point_mm[c];
    EXPECT_LT(std::sqrt(z2[c]), 1.1) << "coordinate " << c << ": u " << split.misfit_at_point_mm[c];
  }
  EXPECT_NEAR(split.misfit_mm, kAmplitude, 0.1 * kAmplitude);  // both axes' sqrt(1/2) in quadrature
}

}  // namespace
}  // namespace fvm::artefacts
