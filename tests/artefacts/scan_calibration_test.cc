// Calibration from stitched scans of a textured part (issue 21): tiles rendered where a stage with known errors
// puts every pixel, registered as a chain, identified from the displacements between neighbours.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "artefacts/scan_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "stage/calibration.h"
#include <cstdlib>

namespace fvm::artefacts {
namespace {

constexpr double kFov5xMm = 2.82;  // FACTS: 5x lens, field of view

StageTruth PublishedSizeStage(unsigned seed, double periodic_um) {
  FvmBatchOptions batch;
  batch.seed = seed;
  batch.validation_placements = 0;
  const FvmBatchTruth t = SimulateFvmBatch(batch).truth;  // 125 um mean error, guideways turning tens of urad
  return StageTruth{t.layout, t.values, periodic_um, 25.0};
}

std::vector<RegisteredScan> ScanAndRegister(const StageTruth& truth, const std::vector<double>& heights, int tile_px,
                                            double* pixel_mm) {
  imaging::CalibrationScanOptions plan;
  plan.heights_mm = heights;
  imaging::TilePlanOptions lens;
  lens.fov_mm = kFov5xMm;
  lens.overlap = 0.25;
  ScanSimulationOptions options;
  options.tile_px = tile_px;
  options.pixel_mm = kFov5xMm / tile_px;
  options.camera = ScanTexture("ground");
  if (getenv("VIG")) options.camera.vignetting = atof(getenv("VIG"));
  *pixel_mm = options.pixel_mm;
  std::vector<RegisteredScan> registered;
  for (SimulatedScan& scan : SimulateScans(truth, imaging::PlanCalibrationScans(plan, lens), options)) {
    std::vector<Eigen::Vector2d> nominal;
    for (const Eigen::Vector3d& e : scan.encoder_mm) {
      nominal.push_back(Eigen::Vector2d(e.x() - scan.encoder_mm[0].x(), scan.encoder_mm[0].y() - e.y()) / options.pixel_mm);
    }
    registered.push_back({scan.name, scan.encoder_mm, imaging::RegisterTileChain(scan.images, nominal, {})});
  }
  return registered;
}

// The xy stage error a calibration predicts against the truth's, over validation positions spread over the scanned
// square, once the rigid motion in xy (offset and turn about z) that no image can tell is removed: rms and max, um.
struct XyComparison {
  double rms_um = 0, max_um = 0;
};
XyComparison CompareInXy(const stage::Calibration& cal, const StageTruth& truth, double z) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> coordinate(-170.0, -30.0);
  std::vector<Eigen::Vector2d> q, d;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p(coordinate(random), coordinate(random), z);
    q.push_back(p.head<2>());
    d.push_back((truth.Forward(p) - stage::Forward(cal.layout, cal.values, p)).head<2>());
  }
  // d ~ t + theta (-y, x): least squares, written out here.
  Eigen::MatrixXd a(2 * q.size(), 3);
  Eigen::VectorXd b(2 * q.size());
  for (size_t i = 0; i < q.size(); ++i) {
    a.row(2 * i) << 1, 0, -q[i].y();
    a.row(2 * i + 1) << 0, 1, q[i].x();
    b.segment<2>(2 * i) = d[i];
  }
  const Eigen::VectorXd rigid = a.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd r = b - a * rigid;
  XyComparison out;
  for (size_t i = 0; i < q.size(); ++i) {
    const double e = r.segment<2>(2 * i).norm() * 1e3;
    out.rms_um += e * e;
    out.max_um = std::max(out.max_um, e);
  }
  out.rms_um = std::sqrt(out.rms_um / q.size());
  return out;
}

TEST(ScanCalibration, DisplacementsBetweenNeighboursRecoverTheStageInXY) {
  const StageTruth truth = PublishedSizeStage(getenv("SEED") ? atoi(getenv("SEED")) : 1, getenv("PER") ? atof(getenv("PER")) : 0.3);
  double pixel_mm = 0;
  const std::vector<RegisteredScan> scans = ScanAndRegister(truth, {-50.0}, getenv("PX") ? atoi(getenv("PX")) : 192, &pixel_mm);
  int accepted = 0, pairs = 0;
  for (const RegisteredScan& s : scans) {
    for (const auto& p : s.registration.pairs) accepted += p.accepted, ++pairs;
  }
  EXPECT_EQ(accepted, pairs);
  if (getenv("PAIRS")) {
    for (const RegisteredScan& sc : scans) {
      double sx = 0, sy = 0, mx = 0, my = 0; int n = 0;
      for (const auto& p : sc.registration.pairs) {
        const Eigen::Vector3d a = sc.encoder_mm[p.a], b = sc.encoder_mm[p.b];
        const Eigen::Matrix3d t = 0.5 * (truth.Camera(a).inverse() + truth.Camera(b).inverse());
        const Eigen::Vector3d pred = t * (truth.Forward(b) - truth.Forward(a));
        const Eigen::Vector2d meas(p.offset_px.x() * pixel_mm, -p.offset_px.y() * pixel_mm);
        const Eigen::Vector2d d = (meas - pred.head<2>()) * 1e3;
        sx += d.x(); sy += d.y(); mx += d.x()*d.x(); my += d.y()*d.y(); ++n;
      }
      std::printf("%s: mean %.4f %.4f um, rms %.4f %.4f um\n", sc.name.c_str(), sx/n, sy/n, std::sqrt(mx/n), std::sqrt(my/n));
    }
  }
  stage::IdentificationOptions options;
  options.frame = stage::StitchedFrame::kRotated;
  const stage::MeasurementSet set = ScanDisplacements(scans, pixel_mm);
  options.anchors = set.anchors;
  const stage::IdentificationResult fit = stage::Identify(stage::FvmModelLayout("27"), set.observations, options);
  const XyComparison turned = CompareInXy(fit.calibration, truth, -50.0);

  stage::IdentificationOptions naive_options = options;
  naive_options.anchor = stage::Anchor::kFirstTile;
  const stage::MeasurementSet positions = ScanPositions(scans, pixel_mm);
  const stage::IdentificationResult naive = stage::Identify(stage::FvmModelLayout("27"), positions.observations, naive_options);
  const XyComparison chained = CompareInXy(naive.calibration, truth, -50.0);
  std::printf("displacements: %.3f rms %.3f max um; chained positions: %.3f rms %.3f max um; fit rms %.3f um, weighted %.2f\n",
              turned.rms_um, turned.max_um, chained.rms_um, chained.max_um, fit.rms_mm * 1e3, fit.weighted_rms);
  double u2 = 0;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d q(-170 + 14 * (i % 10), -170 + 14 * (i / 10), -50);
    const Eigen::Matrix3d c = stage::Correct(fit.calibration, q).covariance;
    u2 += c(0, 0) + c(1, 1);
  }
  std::printf("predicted %.3f um\n", std::sqrt(u2 / 100) * 1e3);
  if (getenv("FIXED")) for (const auto& f : fit.fixed) std::printf("  fixed %s: %s\n", f.name.c_str(), f.reason.c_str());
  EXPECT_LT(turned.rms_um, 1.0);
}

}  // namespace
}  // namespace fvm::artefacts
