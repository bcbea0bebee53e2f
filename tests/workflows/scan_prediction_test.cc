// Issue 31: the scan calibration's printed xy prediction against the truth of the stage it was made on. Tiles are
// rendered where a stage with known errors and a lead screw's 0.3 um cycle puts every pixel (the simulator of
// `fvm simulate scan`), registered and fitted by the job `fvm calibrate --scan` runs.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <vector>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "artefacts/simulation/stage_truth.h"
#include "imaging/tile_plan.h"
#include "stage/parameter_layout.h"
#include "workflows/calibrate.h"

namespace fvm::workflows {
namespace {

// The stage of `fvm simulate fvm-batch --seed N` (125 um mean error) with the 0.3 um cycle `fvm simulate scan` adds.
artefacts::StageTruth ScanPredictionStage(unsigned seed) {
  artefacts::FvmBatchOptions batch;
  batch.seed = seed;
  batch.validation_placements = 0;
  const artefacts::FvmBatchTruth t = artefacts::SimulateFvmBatch(batch).truth;
  return artefacts::StageTruth{t.layout, t.values, 0.3, 25.0};
}

// A row, a column and a diagonal of 150 mm, 256 px tiles of the 5x lens' 2.82 mm field, 25 % overlap, ground texture.
std::vector<artefacts::RegisteredScan> ScanPredictionScans(const artefacts::StageTruth& truth, double pixel_mm) {
  imaging::TilePlanOptions lens;
  lens.fov_mm = 2.82;
  lens.overlap = 0.25;
  artefacts::ScanSimulationOptions render;
  render.tile_px = 256;
  render.pixel_mm = pixel_mm;
  render.camera = artefacts::ScanTexture("ground");
  std::vector<artefacts::RegisteredScan> scans;
  for (const auto& scan : artefacts::SimulateScans(truth, imaging::PlanCalibrationScans({}, lens), render)) {
    scans.push_back(artefacts::RegisterScan(scan.name, scan.encoder_mm, scan.images, pixel_mm, false));
  }
  return scans;
}

// What the prediction is defined as, written out here: the xy stage error left after the calibration (truth's
// forward model less the calibration's) on an 11 x 11 grid of the box the scans cover, less the best offset and
// turn about z (a least-squares fit), rms in um.
double ObservedRigidFreeXyUm(const stage::Calibration& cal, const artefacts::StageTruth& truth,
                             const std::vector<artefacts::RegisteredScan>& scans) {
  Eigen::Vector3d lo = scans.front().encoder_mm.front(), hi = lo;
  for (const auto& scan : scans) {
    for (const Eigen::Vector3d& e : scan.encoder_mm) lo = lo.cwiseMin(e), hi = hi.cwiseMax(e);
  }
  Eigen::MatrixXd a(2 * 121, 3);
  Eigen::VectorXd b(2 * 121);
  for (int i = 0; i < 121; ++i) {
    const Eigen::Vector3d q(lo.x() + (hi.x() - lo.x()) * (i % 11) / 10.0, lo.y() + (hi.y() - lo.y()) * (i / 11) / 10.0,
                            scans.front().encoder_mm.front().z());
    a.row(2 * i) << 1, 0, -q.y();
    a.row(2 * i + 1) << 0, 1, q.x();
    b.segment<2>(2 * i) = (truth.Forward(q) - stage::Forward(cal.layout, cal.values, q)).head<2>();
  }
  return (b - a * a.colPivHouseholderQr().solve(b)).norm() / std::sqrt(121.0) * 1e3;
}

// The figure `fvm calibrate --scan` prints (the coefficients' share with the misfit along the scans) against the
// error seen, on seeds 1-4. One calibration draws the registrations' sub-pixel gain once per coordinate and the
// lead screw's phase once per scan (scan_correlated_errors.h), so its error scatters about the prediction like a
// chi-square of a few degrees of freedom (observed / predicted on seeds 1-4: 1.07, 0.83, 1.06, 0.70, where seed 4
// has one poor pair that widens the white part; pooled 0.89, with each axis' misfit counted at every point, issue
// 43; 1.12, 0.86, 1.11, 0.73, pooled 0.93, when one axis' was; seeds 5-8 then: 1.18, 0.79, 1.14, 1.03): the
// ratio is judged on the mean squares pooled over the four, within 0.8-1.25 as issue 31 asks, and each seed within
// a factor of two.
TEST(CalibrateScans, PredictedXyErrorMatchesTheObservedPooledOverSeeds) {
  const double pixel_mm = 2.82 / 256;
  double observed2 = 0, predicted2 = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const artefacts::StageTruth truth = ScanPredictionStage(seed);
    const std::vector<artefacts::RegisteredScan> scans = ScanPredictionScans(truth, pixel_mm);
    ScanCalibrateOptions options;
    options.pixel_mm = pixel_mm;
    options.settings.stitched_frame = "rotated";
    const ScanCalibrationResult r = CalibrateScans(scans, options);
    ASSERT_TRUE(r.fitted.result.converged) << "seed " << seed;
    const double predicted = r.predicted_xy_with_misfit_um;
    const double observed = ObservedRigidFreeXyUm(r.fitted.result.calibration, truth, scans);
    EXPECT_GT(observed / predicted, 0.5) << "seed " << seed << ": predicted " << predicted << " um, observed " << observed;
    EXPECT_LT(observed / predicted, 2.0) << "seed " << seed << ": predicted " << predicted << " um, observed " << observed;
    observed2 += observed * observed;
    predicted2 += predicted * predicted;
  }
  const double ratio = std::sqrt(observed2 / predicted2);
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.25);
}

}  // namespace
}  // namespace fvm::workflows
