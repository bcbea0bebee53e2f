// The frame of a stitched measurement (stage/stitched_frame.h) against the convention written out from [Pérez 2019] eq.
// 1 in the test (published_model.h): the export keeps the orientation the camera had at its first tile a,
// s = a + R_Y R_X (at a) (P(q) - P(a)).

#include "stage/stitched_frame.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "tests/stage/published_model.h"

namespace fvm::stage {
namespace {

// The published error functions of a truth at q, read through the truth's own term values (the frame, not the
// polynomials, is under test here).
testing::PublishedErrors ErrorsOf(const ParameterLayout& layout, const std::vector<double>& values, const Eigen::Vector3d& q) {
  std::vector<double> all(layout.coefficients().size());
  layout.Expand(values.data(), all.data());
  double e[kNumErrorTerms];
  layout.TermValues(all.data(), q, e);
  std::map<std::string, double> v;
  for (int t = 0; t < kNumErrorTerms; ++t) v[std::string(GetErrorTerm(t).vdi)] = e[t];
  return {v["xTx"], v["xTy"], v["xTz"], v["yTx"], v["yTy"], v["yTz"], v["xRx"], v["xRy"],
          v["xRz"], v["yRx"], v["yRy"], v["yRz"], v["xWy"], v["xWz"], v["yWz"]};
}

TEST(StitchedFrame, SimulatedExportsTurnWithTheStageAtTheirFirstTile) {
  for (unsigned seed : {1u, 2u}) {
    artefacts::FvmBatchOptions options;
    options.seed = seed;
    options.noise_um = 0.0;
    const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
    options.stitched_frame = StitchedFrame::kTranslated;
    const artefacts::SimulatedFvmBatch translated = artefacts::SimulateFvmBatch(options);
    const auto part = [&](const Eigen::Vector3d& q) {
      return testing::PublishedEquation1(ErrorsOf(sim.truth.layout, sim.truth.values, q), q);
    };
    double largest_turn_effect = 0.0;
    for (size_t p = 0; p < sim.batch.placements.size(); ++p) {
      const artefacts::Placement& placement = sim.batch.placements[p];
      const Eigen::Vector3d a = testing::PublishedFirstTile(placement.free);
      const testing::PublishedErrors e = ErrorsOf(sim.truth.layout, sim.truth.values, a);
      const Eigen::Matrix3d turn = testing::PublishedRotation(e.yRx, e.yRy, e.yRz) * testing::PublishedRotation(e.xRx, e.xRy, e.xRz);
      for (size_t i = 0; i < placement.free.size(); ++i) {
        const Eigen::Vector3d expected = a + turn * (part(placement.free[i]) - part(a));
        EXPECT_LT((placement.stitched[i] - expected).norm(), 1e-9) << placement.name << " calotte " << i + 1;
        largest_turn_effect = std::max(largest_turn_effect, (translated.batch.placements[p].stitched[i] - expected).norm());
      }
    }
    // The turn is tens of microradians over lever arms of up to 200 mm: micrometres, far above the comparison.
    EXPECT_GT(largest_turn_effect, 1e-3) << "seed " << seed;
  }
}

TEST(StitchedFrame, TurnDerivativesMatchFiniteDifferences) {
  artefacts::FvmBatchOptions options;
  options.seed = 4;
  const artefacts::FvmBatchTruth truth = artefacts::SimulateFvmBatch(options).truth;
  const Eigen::Vector3d a(-150, -30, -50), r(-185, -15, -50);
  std::vector<Eigen::Matrix3d> jacobian;
  FirstTileTurn(StitchedFrame::kRotated, truth.layout, truth.values.data(), a, &r, &jacobian);
  ASSERT_EQ(jacobian.size(), truth.values.size());
  for (size_t k = 0; k < truth.values.size(); ++k) {
    std::vector<double> up = truth.values, down = truth.values;
    const double h = 1e-6;
    up[k] += h;
    down[k] -= h;
    const Eigen::Matrix3d numeric = (FirstTileTurn(StitchedFrame::kRotated, truth.layout, up.data(), a, &r) -
                                     FirstTileTurn(StitchedFrame::kRotated, truth.layout, down.data(), a, &r)) / (2 * h);
    EXPECT_LT((jacobian[k] - numeric).norm(), 1e-6) << truth.layout.FreeNames()[k];
  }
  // Translated: no turn, nothing depends on the coefficients.
  EXPECT_TRUE(FirstTileTurn(StitchedFrame::kTranslated, truth.layout, truth.values.data(), a, &r, &jacobian).isIdentity());
  EXPECT_TRUE(jacobian.front().isZero());
}

TEST(StitchedFrame, FitTurnRecoversATurnAboutTheFirstTile) {
  // A bar from the first tile, turned by 40 urad of yaw and 15 urad of pitch about it, with 0.5 um noise.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 5e-4);
  const Eigen::Vector3d w(0.0, 15e-6, 40e-6);
  std::vector<Eigen::Vector3d> arms, residuals;
  for (int i = 0; i < 17; ++i) {
    arms.emplace_back(10.0 * i * 0.8, -10.0 * i * 0.6, 0.01 * i);
    residuals.push_back(TurnDisplacement(w, arms.back()) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  const TurnFit fit = FitTurn(residuals, arms);
  // The noise of a slope over 160 mm from 17 points: about 0.5 um / (160 mm * 1.3) ~ 2.5 urad; 4 sigma.
  EXPECT_NEAR(fit.rotation.z(), w.z(), 10e-6);
  // Turning a bar about its own length moves nothing: that component (-9 urad of w) is left at zero, not amplified.
  EXPECT_NEAR(fit.rotation.dot(Eigen::Vector3d(0.8, -0.6, 0.0)), 0.0, 1e-7);
}

// Identification in the rotated frame on placements that start apart: each has its own turn, which a translated
// frame cannot follow. Independent data (eq. 1 written out), guideways that turn by up to 2e-4 rad per 100 mm so
// that starts up to 30 mm apart turn the placements visibly against each other.
TEST(StitchedFrame, IdentificationFollowsTheTurnOfPlacementsThatStartApart) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const testing::PublishedStage stage = testing::PublishedStage::Draw(seed);
    const testing::PublishedMeasurements m = testing::MeasureOnPublishedStage(stage, seed, 5e-4, 10, /*apart=*/true, /*turned=*/true);
    ParameterLayout layout = FvmModelLayout("27");
    IdentificationOptions options;
    options.anchor = Anchor::kFirstTile;
    options.anchors = m.identify.anchors;
    options.frame = StitchedFrame::kTranslated;
    const IdentificationResult translated = Identify(layout, m.identify.observations, options);
    options.frame = StitchedFrame::kRotated;
    const IdentificationResult rotated = Identify(layout, m.identify.observations, options);
    ASSERT_TRUE(rotated.converged);
    // Noise of 0.5 um per coordinate in both measurements: 1.22 um rms of the 3-D residual, less what the fit takes.
    EXPECT_LT(rotated.residual_summary.rms_mm, 1.3e-3) << "seed " << seed;
    EXPECT_LT(rotated.residual_summary.rms_mm, translated.residual_summary.rms_mm) << "seed " << seed;
    ASSERT_TRUE(rotated.calibration.frame_reference.has_value());
    EXPECT_TRUE(rotated.calibration.frame_reference->isApprox(m.identify.anchors.front()));
  }
}

}  // namespace
}  // namespace fvm::stage
