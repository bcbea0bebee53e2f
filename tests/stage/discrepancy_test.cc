// The discrepancy workflow on simulated batches in which one effect is hidden (artefacts/), and on clean ones.

#include "stage/discrepancy.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "artefacts/batch_observations.h"
#include "artefacts/fvm_batch_simulation.h"
#include "stage/fvm_stage_models.h"

namespace fvm::stage {
namespace {

struct Case {
  std::string effect;
  std::string model;  // base model = the truth's model (the effect is what it lacks)
  double height_step_mm = 0.0;
};

Diagnosis DiagnoseCase(const Case& c, unsigned seed) {
  artefacts::FvmBatchOptions options;
  options.seed = seed;
  options.truth_model = c.model;
  options.hidden_effect = c.effect;
  options.height_step_mm = c.height_step_mm;
  const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
  return Diagnose(FvmModelLayout(c.model), artefacts::Observations(sim.batch, sim.batch.identify),
                  artefacts::Observations(sim.batch, sim.batch.validate));
}

// Each effect hidden on top of a truth of the base model's form, at realistic sizes (see FvmBatchOptions): the
// workflow must name it, and the gap on the held-out placements must at least halve. Effects like a linear drift
// or a quadratic positioning error partly hide inside the stage model's own terms.
class HiddenEffect : public ::testing::TestWithParam<Case> {};

TEST_P(HiddenEffect, IsNamedAndTheGapHalves) {
  const Case& c = GetParam();
  for (unsigned seed : {1u, 2u, 3u}) {
    const Diagnosis d = DiagnoseCase(c, seed);
    ASSERT_TRUE(d.effect.has_value()) << c.effect << " seed " << seed << ": " << d.explanation;
    EXPECT_EQ(*d.effect, c.effect) << "seed " << seed;
    EXPECT_LE(d.validation_after.mean_mm, 0.5 * d.validation_before.mean_mm) << c.effect << " seed " << seed;
    EXPECT_LE(d.after.mean_mm, d.before.mean_mm) << c.effect << " seed " << seed;
    EXPECT_GT(std::abs(d.size), 3 * d.size_u) << c.effect << " seed " << seed;  // a real, resolved effect
    EXPECT_FALSE(d.explanation.empty());
  }
}

INSTANTIATE_TEST_SUITE_P(Catalogue, HiddenEffect,
                         ::testing::Values(Case{"thermal_drift", "27"}, Case{"higher_order", "27"},
                                           Case{"reference_anchor", "27"}, Case{"z_coupling", "9", 20.0},
                                           Case{"outliers", "27"}, Case{"scale", "15"}),
                         [](const auto& info) { return info.param.effect; });

TEST(Discrepancy, NamesTheComponentAndSizeOfTheEffect) {
  const Diagnosis order = DiagnoseCase({"higher_order", "27"}, 2);
  EXPECT_EQ(order.component, "xTx");
  const Diagnosis drift = DiagnoseCase({"thermal_drift", "27"}, 2);
  EXPECT_EQ(drift.component, "x");  // the simulated drift is mostly along x: 3 um/min
  EXPECT_NEAR(drift.size, 3.0, 3 * drift.size_u);
  const Diagnosis scale = DiagnoseCase({"scale", "15"}, 2);
  EXPECT_NEAR(std::abs(scale.size), 300.0, 3 * scale.size_u);  // ppm
  EXPECT_EQ(scale.size_unit, "ppm");
}

TEST(Discrepancy, CleanDataRarelyRaisesAnAlarm) {
  // The selection runs at a 1 % family-wise level per batch; over 60 clean batches of three model forms the
  // expected count is below 1. The issue allows 5 % (3 of 60).
  int alarms = 0, batches = 0;
  for (const Case& c : {Case{"", "27"}, Case{"", "9", 20.0}, Case{"", "15"}}) {
    for (unsigned seed = 100; seed < 120; ++seed) {
      const Diagnosis d = DiagnoseCase(c, seed);
      alarms += d.effect.has_value();
      ++batches;
      EXPECT_EQ(d.after.mean_mm, d.before.mean_mm);
    }
  }
  EXPECT_LE(alarms, 3) << alarms << " false alarms in " << batches << " clean batches";
}

TEST(Discrepancy, ResidualAnalysisPointsAtWhatIsWrong) {
  EXPECT_THAT(DiagnoseCase({"outliers", "27"}, 1).findings, ::testing::Contains(::testing::HasSubstr("largest residual")));
  EXPECT_THAT(DiagnoseCase({"reference_anchor", "27"}, 3).findings, ::testing::Contains(::testing::HasSubstr("off on average")));
  EXPECT_THAT(DiagnoseCase({"", "27"}, 1).findings, ::testing::ElementsAre(::testing::HasSubstr("no structure")));
}

}  // namespace
}  // namespace fvm::stage
