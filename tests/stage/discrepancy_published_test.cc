// The discrepancy workflow on data it did not make: measurements of the published equation written out in
// tests/stage/published_model.h, with the hidden effects written out there too. Nothing of artefacts/ is used, so
// the simulator and the workflow cannot share a mistake. These are the three weaknesses issue 14 found on an
// independent generator: a scale that a wrong first candidate hid, two effects at once, and blunders that drag good
// neighbours over the limit.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "stage/discrepancy.h"
#include "stage/fvm_stage_models.h"
#include "tests/stage/published_model.h"
#include "tests/support/named_effects.h"

namespace fvm::stage {
namespace {

using testing::MeasureOnPublishedStage;
using testing::PublishedEffects;
using testing::PublishedMeasurements;
using testing::PublishedStage;

constexpr double kNoiseMm = 5e-4;  // 0.5 um per coordinate, in both measurements

// A stage of the 15 model's form (constant error functions), or of the 27 model's (straight lines), with the
// published magnitudes; `bend_mm`: xTx's second order.
PublishedStage Stage(unsigned seed, bool linear, double bend_mm = 0.0) {
  PublishedStage stage = PublishedStage::Draw(seed, 0.0, 3e-5);
  if (!linear) stage.slope.fill(0.0);
  stage.bend_mm = bend_mm;
  return stage;
}

using testing::Named;

Diagnosis DiagnosePublished(const std::string& model, const PublishedMeasurements& m) {
  return Diagnose(FvmModelLayout(model), m.identify, m.validate);
}

// The dead end: a 300 ppm lens scale. Anchoring each placement at its first tile fits the identification
// data too but makes the held-out placements worse; the scale explains both.
TEST(DiscrepancyOnPublishedData, NamesAScaleThatAnotherCandidateOutscores) {
  for (unsigned seed : {1u, 2u, 3u}) {
    PublishedEffects effects;
    effects.scale = seed % 2 ? 3e-4 : -3e-4;
    const Diagnosis d = DiagnosePublished("15", MeasureOnPublishedStage(Stage(seed, false), seed, kNoiseMm, 10, false, false, effects));
    ASSERT_FALSE(d.steps.empty()) << "seed " << seed << ": " << d.explanation;
    EXPECT_EQ(d.steps.front().effect, "scale") << "seed " << seed;
    EXPECT_NEAR(d.steps.front().size, effects.scale * 1e6, 3 * d.steps.front().size_u + 5.0) << "seed " << seed;  // ppm
    EXPECT_LE(d.validation_after.mean_mm, 0.5 * d.validation_before.mean_mm) << "seed " << seed;
  }
}

// A drift of 3 um/min and a scale together, on the 15 model: both named, the gap at least halved, the drift's
// size within its uncertainty (plus 10 % of it, for the linearised estimate).
TEST(DiscrepancyOnPublishedData, NamesADriftAndAScaleTogether) {
  for (unsigned seed : {1u, 2u, 3u}) {
    PublishedEffects effects;
    effects.scale = 3e-4;
    effects.drift_mm_per_s = Eigen::Vector3d(3e-3, -1.5e-3, 0.9e-3) / 60.0;
    const Diagnosis d = DiagnosePublished("15", MeasureOnPublishedStage(Stage(seed, false), seed, kNoiseMm, 10, false, false, effects));
    EXPECT_THAT(Named(d), ::testing::IsSupersetOf({"thermal_drift", "scale"})) << "seed " << seed << ": " << d.explanation;
    for (const DiagnosisStep& s : d.steps) {
      if (s.effect == "thermal_drift") {
        EXPECT_NEAR(s.size, 3.0, 3 * s.size_u + 0.3) << "seed " << seed;  // um/min along x
      }
    }
    EXPECT_LE(d.validation_after.mean_mm, 0.5 * d.validation_before.mean_mm) << "seed " << seed;
  }
}

// A bend of xTx (40 um at the far end of x) and three 80 um blunders, on the 27 model: both named, only the
// blunders flagged, the gap at least halved.
TEST(DiscrepancyOnPublishedData, NamesABendAndBlundersWithoutFlaggingGoodCentres) {
  for (unsigned seed : {1u, 2u, 3u}) {
    PublishedEffects effects;
    effects.blunders = 3;
    const PublishedStage stage = Stage(seed, true, 0.01);
    const PublishedMeasurements m = MeasureOnPublishedStage(stage, seed, kNoiseMm, 10, false, false, effects);
    const PublishedMeasurements clean = MeasureOnPublishedStage(stage, seed, kNoiseMm, 10, false, false, {});
    std::set<std::string> truth;
    for (size_t i = 0; i < m.identify.observations.size(); ++i) {
      if (m.identify.observations[i].command != clean.identify.observations[i].command) truth.insert(std::to_string(i));
    }
    ASSERT_EQ(truth.size(), 3u);
    const Diagnosis d = DiagnosePublished("27", m);
    EXPECT_THAT(Named(d), ::testing::IsSupersetOf({"higher_order", "outliers"})) << "seed " << seed << ": " << d.explanation;
    std::set<std::string> flagged;
    for (const DiagnosisStep& s : d.steps) {
      if (s.effect == "higher_order") {
        EXPECT_EQ(s.component, "xTx") << "seed " << seed;
      }
      if (s.effect != "outliers") continue;
      std::stringstream names(s.component);
      for (std::string name; std::getline(names, name, ',');) flagged.insert(name);
    }
    EXPECT_EQ(flagged, truth) << "seed " << seed;
    EXPECT_LE(d.validation_after.mean_mm, 0.5 * d.validation_before.mean_mm) << "seed " << seed;
  }
}


// The case: a drift and a scale, the identification bars on 20 mm wedges measured each in one direction
// (their height grows with time: a drift and pitch and roll look alike), the exports not turned. The held-out
// placements refuse the drift, rightly; then nothing may be named for what it leaves, above all not frame_rotation,
// which is not in these data: the residual left and its likeliest cause are said instead. On the 9, 15 and 27
// models alike.
TEST(DiscrepancyOnPublishedData, NamesNothingForWhatARefusedDriftLeaves) {
  // Seeds 1-3 whose drift is not named: none on the 9 model (without pitch and roll, the drift's pattern along the
  // wedges is its own, and it is named rightly), two on the 15 (the held-out placements refuse it), all three on the
  // 27 (its linear terms take the drift: no candidate at all, and the turns would take what it leaves).
  const std::map<std::string, int> expected_refusals{{"9", 0}, {"15", 2}, {"27", 3}};
  for (const char* model : {"9", "15", "27"}) {
    int refusals = 0;
    for (unsigned seed : {1u, 2u, 3u}) {
      PublishedEffects effects;
      effects.scale = 3e-4;
      effects.drift_mm_per_s = Eigen::Vector3d(3e-3, -1.5e-3, 0.9e-3) / 60.0;
      effects.rise_mm = 20.0;
      const Diagnosis d = DiagnosePublished(model, MeasureOnPublishedStage(Stage(seed, false), seed, kNoiseMm, 10, false, false, effects));
      EXPECT_THAT(Named(d), ::testing::Not(::testing::Contains("frame_rotation"))) << model << " seed " << seed << ": " << d.unexplained;
      // A drift named is this case identified; otherwise it must be named as the likeliest cause of what is left,
      // with the reason the data could not show it (the held-out placements refused it, or it took the turns' place).
      const std::vector<std::string> named = Named(d);
      if (std::find(named.begin(), named.end(), "thermal_drift") != named.end()) continue;
      ++refusals;
      const bool reason = std::any_of(d.notes.begin(), d.notes.end(), [](const std::string& n) {
        return (n.find("thermal_drift fits the identification data better but makes the held-out placements worse") !=
                    std::string::npos &&
                n.find("measuring every other placement backwards") != std::string::npos) ||
               n.find("a drift grows from each first tile as a turn does") != std::string::npos;
      });
      EXPECT_TRUE(reason) << model << " seed " << seed;
      EXPECT_THAT(d.unexplained, ::testing::StartsWith("unexplained: ")) << model << " seed " << seed;
      EXPECT_THAT(d.unexplained, ::testing::ContainsRegex("the likeliest cause is (the refused )?a? ?thermal_drift"))
          << model << " seed " << seed;
    }
    EXPECT_EQ(refusals, expected_refusals.at(model)) << model;
  }
}

}  // namespace
}  // namespace fvm::stage
