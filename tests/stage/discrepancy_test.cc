// The discrepancy workflow on simulated batches in which one effect is hidden (artefacts/), and on clean ones.

#include "stage/discrepancy.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <sstream>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "stage/fvm_stage_models.h"
#include "tests/support/named_effects.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

struct Case {
  std::string effect;
  std::string model;  // base model = the truth's model (the effect is what it lacks)
  double height_step_mm = 0.0;
  bool serpentine = false;
  std::string terms = {};  // a base model of one's own (stage::ComposeLayout) instead of `model`
};

// One effect hidden at a time: the exports keep the translated frame, since the turn of a stitched frame is itself
// an effect of the catalogue (frame_rotation, below).
Diagnosis DiagnoseCase(const Case& c, unsigned seed, StitchedFrame frame = StitchedFrame::kTranslated) {
  artefacts::FvmBatchOptions options;
  options.seed = seed;
  options.stitched_frame = frame;
  options.truth_model = c.model;
  options.hidden_effect = c.effect;
  options.height_step_mm = c.height_step_mm;
  options.serpentine = c.serpentine;
  options.truth_terms = c.terms;
  const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
  return Diagnose(c.terms.empty() ? FvmModelLayout(c.model) : ComposeLayout(c.terms),
                  artefacts::Observations(sim.batch, sim.batch.identify), artefacts::Observations(sim.batch, sim.batch.validate));
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
  // expected count is below 1 (1 today). The issue allows 5 % (3 of 60).
  int alarms = 0, batches = 0;
  std::string named;
  for (const Case& c : {Case{"", "27"}, Case{"", "9", 20.0}, Case{"", "15"}}) {
    for (unsigned seed = 100; seed < 120; ++seed) {
      const Diagnosis d = DiagnoseCase(c, seed);
      alarms += d.effect.has_value();
      if (d.effect) named += " " + *d.effect + "(" + c.model + ", seed " + std::to_string(seed) + ")";
      ++batches;
      EXPECT_EQ(d.after.mean_mm, d.before.mean_mm);
    }
  }
  EXPECT_LE(alarms, 3) << alarms << " false alarms in " << batches << " clean batches:" << named;
}

// Exports that keep the orientation of their first tile (the default of the simulator, what an instrument that
// registers tiles by translation gives): identification placements share a start and the turn, so only the
// held-out ones show it. Named on every seed, with the held-out figure after the step close to what a rigid fit per
// placement leaves; never on exports without the turn.
TEST(Discrepancy, NamesTheTurnOfTheStitchedFrame) {
  for (unsigned seed : {1u, 2u, 3u}) {
    artefacts::FvmBatchOptions options;
    options.seed = seed;
    const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
    const MeasurementSet identify = artefacts::Observations(sim.batch, sim.batch.identify);
    const MeasurementSet validate = artefacts::Observations(sim.batch, sim.batch.validate);
    const Diagnosis d = Diagnose(FvmModelLayout("27"), identify, validate);
    ASSERT_TRUE(d.effect.has_value()) << "seed " << seed << ": " << d.explanation;
    EXPECT_EQ(*d.effect, "frame_rotation") << "seed " << seed;
    EXPECT_EQ(d.size_unit, "urad");
    EXPECT_EQ(d.turns.size(), validate.anchors.size());
    EXPECT_GT(d.size, 3 * d.size_u) << "seed " << seed;
    IdentificationOptions id;
    id.anchors = identify.anchors;
    const IdentificationResult fit = Identify(FvmModelLayout("27"), identify.observations, id);
    const FrameFreeStats rigid = RigidValidation(&fit.calibration, validate.observations);
    EXPECT_LE(d.validation_after.rms_mm, 1.15 * rigid.rms_mm) << "seed " << seed;  // the target
    EXPECT_LT(d.validation_after.rms_mm, d.validation_before.rms_mm) << "seed " << seed;
    EXPECT_FALSE(DiagnoseCase({"", "27"}, seed).effect.has_value()) << "seed " << seed << ": translated exports";
  }
}

using testing::Named;

// The design a pair of hidden effects needs, as in tests/bench/discrepancy_pairs.sh: the 27 model; the 15 model
// where a scale is hidden (27's linear terms take a scale about a shared start exactly, and no data of one
// instrument tell them apart); the 9 model on a 20 mm wedge where z_coupling is hidden (15 and 27 have pitch and
// roll), measured serpentine (along a bar on a wedge, height and time grow together); both: the 15 model's
// constant terms without pitch and roll.
Case PairCase(const std::string& a, const std::string& b) {
  const bool scale = a == "scale" || b == "scale", z = a == "z_coupling" || b == "z_coupling";
  Case c{a + "," + b, scale ? "15" : "27"};
  if (z) c.model = "9", c.height_step_mm = 20.0, c.serpentine = true;
  if (z && scale) c.terms = "xTx:0,xTy:0,xTz:0,yTx:0,yTy:0,yTz:0,xRz:0,yRz:0,xWy:0,xWz:0,yWz:0";
  return c;
}

// Every pair of the catalogue's six effects hidden together, three seeds each: both named, step by step, and the
// held-out gap at least halved. The issue asks for 90 % (41 of 45); all 45 pass today, and two may fail before this
// does (a seed whose effect lands near the noise).
TEST(Discrepancy, NamesTwoEffectsHiddenTogether) {
  const std::vector<std::string> effects = artefacts::HiddenEffectNames();
  int cases = 0, passed = 0;
  std::string failed;
  for (size_t a = 0; a < effects.size(); ++a) {
    for (size_t b = a + 1; b < effects.size(); ++b) {
      for (unsigned seed : {1u, 2u, 3u}) {
        const Diagnosis d = DiagnoseCase(PairCase(effects[a], effects[b]), seed);
        const std::vector<std::string> named = Named(d);
        const bool both = std::count(named.begin(), named.end(), effects[a]) && std::count(named.begin(), named.end(), effects[b]);
        const bool ok = both && d.validation_after.mean_mm <= 0.5 * d.validation_before.mean_mm;
        ++cases;
        passed += ok;
        if (!ok) failed += " " + effects[a] + "," + effects[b] + "/" + std::to_string(seed);
        if (!d.steps.empty()) {
          EXPECT_EQ(*d.effect, d.steps.front().effect);  // the first effect stays where scripts read it
        }
      }
    }
  }
  EXPECT_EQ(cases, 45);
  EXPECT_GE(passed, 43) << "failed:" << failed;
}

// When the best-scoring candidate makes the held-out placements worse, the next one is tried instead of stopping. On
// a wedge measured all in one direction, a drift and pitch and roll both grow along every bar: the drift fits the
// identification data but not the held-out placements (its estimate rests on the little of its pattern that is its
// own), pitch and roll explain both. Measured serpentine, the drift shows at the shared start and both are named.
TEST(Discrepancy, TriesTheNextCandidateInsteadOfStopping) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Diagnosis d = DiagnoseCase({"thermal_drift,z_coupling", "9", 20.0}, seed);
    ASSERT_FALSE(d.steps.empty()) << "seed " << seed;
    EXPECT_EQ(d.steps.front().effect, "z_coupling") << "seed " << seed;
    EXPECT_THAT(d.notes, ::testing::Contains(::testing::HasSubstr("the next candidate was tried"))) << "seed " << seed;
    EXPECT_THAT(d.notes, ::testing::Contains(::testing::HasSubstr("backwards"))) << "seed " << seed;  // the way out
    const Diagnosis serpentine = DiagnoseCase({"thermal_drift,z_coupling", "9", 20.0, true}, seed);
    EXPECT_THAT(Named(serpentine), ::testing::IsSupersetOf({"thermal_drift", "z_coupling"})) << "seed " << seed;
  }
}

// Three 80 um failed sphere fits among 51 centres, over 20 seeds: every one flagged, and (taken out one at a time
// with a refit after each) at most one good centre flagged in all. The truth is where the batch's stitching-free
// centres differ from the same seed's clean batch.
TEST(Discrepancy, FlagsOutliersWithoutSwamping) {
  int missed = 0, false_flags = 0, outliers = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    artefacts::FvmBatchOptions options;
    options.seed = seed;
    options.stitched_frame = StitchedFrame::kTranslated;
    const artefacts::Batch clean = artefacts::SimulateFvmBatch(options).batch;
    options.hidden_effect = "outliers";
    const artefacts::Batch bad = artefacts::SimulateFvmBatch(options).batch;
    std::set<std::string> truth;
    for (size_t p = 0; p < bad.placements.size(); ++p) {
      for (size_t i = 0; i < bad.placements[p].free.size(); ++i) {
        if (bad.placements[p].free[i] != clean.placements[p].free[i]) {
          truth.insert(bad.placements[p].name + ":" + std::to_string(bad.placements[p].ids[i]));
        }
      }
    }
    const Diagnosis d = Diagnose(FvmModelLayout("27"), artefacts::Observations(bad, bad.identify), artefacts::Observations(bad, bad.validate));
    std::set<std::string> flagged;
    for (const DiagnosisStep& s : d.steps) {
      if (s.effect != "outliers") continue;
      std::stringstream names(s.component);
      for (std::string name; std::getline(names, name, ',');) flagged.insert(name);
    }
    for (const std::string& t : truth) missed += !flagged.count(t);
    for (const std::string& f : flagged) false_flags += !truth.count(f);
    outliers += static_cast<int>(truth.size());
  }
  EXPECT_GE(outliers, 50);  // three per batch, fewer where two land on one centre
  EXPECT_EQ(missed, 0);
  EXPECT_LE(false_flags, 1) << "good centres flagged among " << outliers << " outliers in 20 batches";
}

// A warm-up ([Pérez thesis] eqs. 5.1-5.2) that settles within a placement, time constant 2 min, against a drift linear
// in t of the same initial rate (6 um/min): each is named as what it is. The warm-up needs one parameter more and an
// F-test of its own against the linear drift before it competes.
TEST(Discrepancy, TellsAWarmUpFromALinearDrift) {
  for (unsigned seed : {1u, 2u, 3u}) {
    for (double tau_min : {0.0, 2.0}) {
      artefacts::FvmBatchOptions options;
      options.seed = seed;
      options.stitched_frame = StitchedFrame::kTranslated;
      options.hidden_effect = "thermal_drift";
      options.effect_size = 6.0;
      options.drift_tau_min = tau_min;
      const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
      const Diagnosis d = Diagnose(FvmModelLayout("27"), artefacts::Observations(sim.batch, sim.batch.identify),
                                   artefacts::Observations(sim.batch, sim.batch.validate));
      ASSERT_TRUE(d.effect.has_value()) << "seed " << seed;
      EXPECT_EQ(*d.effect, "thermal_drift");
      EXPECT_EQ(d.component, tau_min > 0 ? "x warm-up" : "x") << "seed " << seed << ", tau " << tau_min << " min";
      EXPECT_LE(d.steps.front().validation_after.mean_mm, 0.4 * d.validation_before.mean_mm) << "seed " << seed;
    }
  }
}

TEST(Discrepancy, ResidualAnalysisPointsAtWhatIsWrong) {
  EXPECT_THAT(DiagnoseCase({"outliers", "27"}, 1).findings, ::testing::Contains(::testing::HasSubstr("largest residual")));
  EXPECT_THAT(DiagnoseCase({"reference_anchor", "27"}, 3).findings, ::testing::Contains(::testing::HasSubstr("off on average")));
  EXPECT_THAT(DiagnoseCase({"", "27"}, 1).findings, ::testing::ElementsAre(::testing::HasSubstr("no structure")));
}

// The same workflow through the same kinematics layer for a machine tool measured by a laser tracker: an XFYZ
// machine ([IJSIMM 2016] workspace 2500 x 1500 x 1200 mm), the tracker pose of [Aguado 2017], first-order Legendre
// errors on all three axes, and a positioning error of X that bends (a second order the model lacks).
TEST(Discrepancy, WorksForAMachineToolSeenByATracker) {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0, 0, -100);
  chain.instrument = Pose::FromEulerXyzDegrees({-863.527, 194.373, 677.782}, {0.0339, 0.0343, 59.4652});
  const std::array<Travel, 3> travel{Travel{0, 2500}, Travel{0, 1500}, Travel{0, 1200}};
  const ParameterLayout base = testing::FullLayout(chain, travel, 1, "xyz", Basis::kLegendre);
  ParameterLayout truth = base;
  truth.SetTerm("xTx", Basis::kLegendre, 2);
  std::vector<double> values = testing::RandomCoefficients(truth, 8, 0.03, 2e-5);
  values[static_cast<size_t>(truth.FreeIndexOf("xTx2"))] = 0.04;  // 40 um of bending at the ends of X

  // Tracker readings with 4 um of noise per coordinate ([Aguado 2017]: range 4 um + angles) on two meshes.
  std::mt19937_64 rng(8);
  std::normal_distribution<double> noise(0.0, 0.004);
  const auto mesh = [&](double shift) {
    MeasurementSet set;
    for (double x = shift; x <= 2500; x += 500)
      for (double y = shift; y <= 1500; y += 500)
        for (double z = shift; z <= 1200; z += 400) {
          const Eigen::Vector3d q(x, y, z);
          const Eigen::Vector3d reading = Forward(truth, values, q) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
          set.observations.push_back({q, reading, 0});
        }
    set.groups = {"mesh"};  // no anchors: tracker readings are not referenced to a first tile
    return set;
  };
  const MeasurementSet identify = mesh(0.0), validate = mesh(250.0);
  const Diagnosis d = Diagnose(base, identify, validate);
  ASSERT_TRUE(d.effect.has_value()) << d.explanation;
  EXPECT_EQ(*d.effect, "higher_order");
  EXPECT_EQ(d.component, "xTx");
  EXPECT_NEAR(d.size, 40.0, 3 * d.size_u);  // um, the Legendre coefficient of order 2
  EXPECT_LE(d.validation_after.mean_mm, 0.5 * d.validation_before.mean_mm);
}

}  // namespace
}  // namespace fvm::stage
