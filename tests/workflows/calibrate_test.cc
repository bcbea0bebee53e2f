#include "workflows/calibrate.h"

#include <gtest/gtest.h>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "artefacts/simulation/stage_truth.h"
#include "core/input_error.h"
#include "imaging/tile_plan.h"

namespace fvm::workflows {
namespace {

artefacts::SimulatedFvmBatch Batch(unsigned seed) {
  artefacts::FvmBatchOptions sim;
  sim.seed = seed;
  return artefacts::SimulateFvmBatch(sim);
}

// The published procedure on a simulated bar batch (125 um mean stage error, 0.5 um centre noise): after the
// model 27 the rigid fit of each validation placement leaves the noise of two exports, sqrt(2) x 0.5 um per
// coordinate (1.2 um of the 3-D norm), not the tens of um before. Bounds: 2 um after, 20 um before.
TEST(CalibrateBatch, CompensatesTheValidationPlacementsDownToTheNoise) {
  const artefacts::SimulatedFvmBatch sim = Batch(4);
  const BatchCalibration c = CalibrateBatch(sim.batch, {});
  ASSERT_TRUE(c.result.converged);
  EXPECT_EQ(c.result.calibration.model, "27");
  ASSERT_TRUE(c.validation.has_value());
  ASSERT_TRUE(c.judged.has_value());
  EXPECT_EQ(&c.Shown(), &*c.validation);
  EXPECT_EQ(c.validation->observations.size(), 17u * sim.batch.validate.size());
  EXPECT_GT(c.judged->before.rigid.rms_mm * 1e3, 20.0);
  EXPECT_LT(c.judged->after.rigid.rms_mm * 1e3, 2.0);
  EXPECT_LT(c.judged->after.distances.rms_mm * 1e3, 2.0);
  EXPECT_GT(c.identification_before.mean_mm * 1e3, 50.0);
  // Every pair of centres of a placement, before and after.
  EXPECT_EQ(c.judged->distance_errors_before_mm.size(), c.judged->distance_errors_after_mm.size());
  EXPECT_EQ(c.judged->distance_errors_after_mm.size(), sim.batch.validate.size() * 16u);  // from the first centre
}

TEST(CalibrateBatch, JudgesTheIdentificationPlacementsOnlyWhenAskedAndNoneAreHeldOut) {
  artefacts::SimulatedFvmBatch sim = Batch(4);
  sim.batch.validate.clear();
  CalibrateOptions options;
  EXPECT_FALSE(CalibrateBatch(sim.batch, options).judged.has_value());
  options.judge_identification = true;
  const BatchCalibration c = CalibrateBatch(sim.batch, options);
  ASSERT_TRUE(c.judged.has_value());
  EXPECT_EQ(&c.Shown(), &c.identification);
}

// A row, a column and a diagonal of 150 mm (256 px tiles of the 5x lens' field) on the simulated stage: the scan
// calibration takes the in-plane distances between the bar's validation centres from tens of um to a few (grey
// tiles see no heights, so z stays; the distances hardly see z on a flat bar).
TEST(CalibrateScans, ShortensTheValidationDistanceErrors) {
  const artefacts::SimulatedFvmBatch sim = Batch(4);
  const artefacts::StageTruth truth{sim.truth.layout, sim.truth.values, 0.0, 25.0};
  imaging::CalibrationScanOptions plan;
  imaging::TilePlanOptions lens;
  lens.fov_mm = 2.82;
  lens.overlap = 0.25;
  artefacts::ScanSimulationOptions render;
  render.tile_px = 256;
  render.pixel_mm = lens.fov_mm / render.tile_px;
  std::vector<artefacts::RegisteredScan> scans;
  for (const auto& scan : artefacts::SimulateScans(truth, imaging::PlanCalibrationScans(plan, lens), render)) {
    scans.push_back(artefacts::RegisterScan(scan.name, scan.encoder_mm, scan.images, render.pixel_mm, false));
  }
  ScanCalibrateOptions options;  // the model 27: a displacement sees no constant term, so order 1 is the least
  options.pixel_mm = render.pixel_mm;
  const ScanCalibrationResult r = CalibrateScans(scans, options, &sim.batch);
  ASSERT_TRUE(r.judged.has_value());
  EXPECT_EQ(r.validation_placements, sim.batch.validate);
  EXPECT_GT(r.predicted_xy_um, 0.0);
  EXPECT_LT(r.judged->after.distances.rms_mm, 0.5 * r.judged->before.distances.rms_mm);
  // 2.3 um at 256 px (1.1 um at 1024 px): the registrations' noise grows as the tiles shrink.
  EXPECT_LT(r.judged->after.distances.rms_mm * 1e3, 4.0);

  // Scans whose pairs all failed are refused, naming the first rejection.
  for (auto& scan : scans) {
    for (auto& pair : scan.registration.pairs) pair.accepted = false, pair.rejection = "quality 0.1 < 0.5";
  }
  try {
    CalibrateScans(scans, options);
    FAIL() << "scans without a registered pair were calibrated";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no pair of neighbouring tiles registered in any scan (first: quality 0.1"),
              std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fvm::workflows
