#include "workflows/correct.h"

#include <gtest/gtest.h>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"

namespace fvm::workflows {
namespace {

// With the stage's true model, the stitching-free centres of a noise-free placement corrected into the first
// tile's frame land on the stitched export's centres: both are what a stitched measurement started at the first
// tile puts there ([Pérez 2019] eq. 1 and the stitched frame, written once in stage/stitched_frame.h). 1 nm
// allows the inverse model's convergence.
TEST(CorrectCentres, TheTrueModelPutsStitchingFreeCentresOnTheStitchedOnes) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 5;
  sim.pitch_error_um = 0.0;
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  stage::Calibration truth{"27", batch.truth.layout, batch.truth.values,
                           Eigen::MatrixXd::Zero(batch.truth.layout.NumFree(), batch.truth.layout.NumFree()), 0.0, std::nullopt, {}};
  const artefacts::Placement& p = batch.exact.Get(batch.exact.validate.front());
  artefacts::CentreExport free;
  for (size_t i = 0; i < p.ids.size(); ++i) free.centres.push_back({p.ids[i], p.free[i], std::nullopt, std::nullopt, std::nullopt, std::nullopt});
  const CentreCorrection c = CorrectCentres(truth, free, stage::StitchedFrame::kRotated, "val.free.csv");
  ASSERT_EQ(c.centres.size(), p.ids.size());
  ASSERT_TRUE(c.first_tile_mm.has_value());
  double worst = 0;
  for (size_t i = 0; i < p.ids.size(); ++i) {
    EXPECT_EQ(c.centres[i].input->id, p.ids[i]);
    worst = std::max(worst, (c.centres[i].position - p.stitched[i]).norm());
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(c.largest_shift_mm, 10e-3);  // the stage's error there, tens of um
  // A covariance of zero gives zero uncertainty.
  EXPECT_EQ(c.centres[0].u.norm(), 0.0);

  // In the stage frame nothing is referred to a first tile.
  EXPECT_FALSE(CorrectCentres(truth, free, std::nullopt, "val.free.csv").first_tile_mm.has_value());
  // An empty export has no first tile, and says so.
  EXPECT_THROW(CorrectCentres(truth, {}, stage::StitchedFrame::kRotated, "empty.csv"), InputError);
}

}  // namespace
}  // namespace fvm::workflows
