// The machine Monte Carlo describes reality: independent noisy measurements of one simulated machine, each
// identified on its own, scatter as much as the Monte Carlo predicts from a single one of them. And it is the same
// bits for any number of threads.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "core/random.h"
#include "stage/fvm_stage_models.h"
#include "artefacts/tracker_observations.h"
#include "stage/monte_carlo.h"

namespace fvm::stage {
namespace {

// The published 75-point study ([Pérez 2019 Sensors] section 3): a 5 x 5 x 3 mesh at 100 mm, here on an XFYZ machine
// with a 100 mm tool.
artefacts::Workspace Workspace() {
  artefacts::Workspace ws;
  ws.max = Eigen::Vector3d(400, 400, 200);
  return ws;
}

AxisChain Chain() {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0, 0, 100);
  chain.instrument = Pose::FromEulerXyzDegrees(Eigen::Vector3d(900, -900, 400), Eigen::Vector3d(0, 0, 30));
  return chain;
}

ParameterLayout Layout() {
  AxisChain chain = Chain();
  chain.instrument.reset();
  return MachineLayout(chain, {Travel{0, 400}, Travel{0, 400}, Travel{0, 200}}, Basis::kLegendre, 2);
}

IdentificationOptions Options() {
  IdentificationOptions o;
  o.instrument = InstrumentPose::kEstimated;
  o.num_threads = 1;
  return o;
}

struct Study {
  artefacts::MachineTruth truth = artefacts::RandomMachineTruth(Chain(), Workspace(), 5);
  std::vector<artefacts::PlannedPoint> points = artefacts::PlanMesh(Workspace(), Eigen::Vector3d(100, 100, 100));
  TrackerNoise noise = TrackerNoise::Preset("published");
  std::vector<Observation> validation;  // noise-free readings of a finer mesh
  Study() {
    const artefacts::TrackerReadings v = artefacts::SimulateTrackerReadings(
        Chain(), truth, artefacts::PlanMesh(Workspace(), Eigen::Vector3d(50, 50, 50)), TrackerNoise::Preset("none"), 1);
    validation = artefacts::TrackerObservations(v, nullptr);
  }
  std::vector<Observation> Readings(std::uint64_t seed) const {
    return artefacts::TrackerObservations(artefacts::SimulateTrackerReadings(Chain(), truth, points, noise, seed), &noise);
  }
};

TEST(MachineMonteCarlo, PredictsTheSpreadOfIndependentMeasurements) {
  const Study study;
  const ParameterLayout layout = Layout();
  // Reality: 24 independent tracker measurements of the same machine, each identified on its own.
  constexpr int kReal = 24;
  std::vector<std::vector<Eigen::Vector3d>> predictions;
  std::optional<VerificationResult> first;
  for (int k = 0; k < kReal; ++k) {
    VerificationResult v = VerifyMachine(layout, study.Readings(100 + static_cast<std::uint64_t>(k)), Options());
    const Calibration& c = v.identified.calibration;
    predictions.push_back(PredictedReadings(c.layout, &c.values, v.identified.pose, study.validation, {}));
    if (k == 0) first.emplace(std::move(v));
  }
  // The Monte Carlo from the first measurement alone.
  MonteCarloOptions mc;
  mc.runs = 48;
  mc.seed = 7;
  const std::vector<MachineMonteCarloRun> runs =
      MachineMonteCarlo(layout, *first, study.Readings(100), study.validation, study.noise, Options(), mc);
  const std::vector<PointSpread> spreads = PointSpreads(runs);
  const size_t n_readings = study.points.size();
  ASSERT_EQ(spreads.size(), n_readings + study.validation.size());

  // Per validation point: the 3D standard deviation of the independent identifications' predictions against the
  // Monte Carlo's, pooled over the points (rms).
  double real_sum = 0, mc_sum = 0;
  for (size_t p = 0; p < study.validation.size(); ++p) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& pr : predictions) mean += pr[p];
    mean /= kReal;
    double var = 0;
    for (const auto& pr : predictions) var += (pr[p] - mean).squaredNorm();
    real_sum += var / (kReal - 1);
    mc_sum += spreads[n_readings + p].covariance.trace();
  }
  const double real_sd_um = 1e3 * std::sqrt(real_sum / static_cast<double>(study.validation.size()));
  const double mc_sd_um = 1e3 * std::sqrt(mc_sum / static_cast<double>(study.validation.size()));
  std::printf("prediction spread (3D sd, rms over %zu points): independent measurements %.2f um, Monte Carlo %.2f um\n",
              study.validation.size(), real_sd_um, mc_sd_um);
  EXPECT_GT(real_sd_um, 1.0);  // the noise matters here: the comparison means something
  EXPECT_NEAR(mc_sd_um / real_sd_um, 1.0, 0.25);

  // Covariance propagation (the fast stand-in used to place the tracker) agrees with the Monte Carlo at the readings.
  const std::vector<Eigen::Matrix3d> predicted = PredictedPointCovariances(
      first->identified.calibration, first->identified.pose, true, study.Readings(100), {}, study.noise);
  ASSERT_EQ(predicted.size(), n_readings);
  double predicted_u95 = 0, mc_u95 = 0;
  for (size_t p = 0; p < n_readings; ++p) {
    predicted_u95 += U95OfCovariance(predicted[p]) / n_readings;
    mc_u95 += spreads[p].u95_mm / n_readings;
  }
  std::printf("mean U95 at the readings: covariance propagation %.2f um, Monte Carlo %.2f um\n", predicted_u95 * 1e3,
              mc_u95 * 1e3);
  EXPECT_NEAR(predicted_u95 / mc_u95, 1.0, 0.25);

  // The validation mean error against repeat measurements: tests/stage/monte_carlo_repeats_test.cc.
  for (const MachineMonteCarloRun& r : runs) EXPECT_TRUE(r.converged);
}

TEST(MachineMonteCarlo, SameBitsForAnyThreadCount) {
  const Study study;
  const ParameterLayout layout = Layout();
  const std::vector<Observation> readings = study.Readings(1);
  const VerificationResult v = VerifyMachine(layout, readings, Options());
  MonteCarloOptions mc;
  mc.runs = 6;
  mc.seed = 42;
  mc.threads = 1;
  const std::vector<MachineMonteCarloRun> one = MachineMonteCarlo(layout, v, readings, {}, study.noise, Options(), mc);
  mc.threads = 2;
  const std::vector<MachineMonteCarloRun> two = MachineMonteCarlo(layout, v, readings, {}, study.noise, Options(), mc);
  ASSERT_EQ(one.size(), two.size());
  for (size_t r = 0; r < one.size(); ++r) {
    EXPECT_EQ(one[r].final.mean_um(), two[r].final.mean_um());
    for (size_t p = 0; p < one[r].deviation_mm.size(); ++p) EXPECT_EQ(one[r].deviation_mm[p], two[r].deviation_mm[p]);
  }
  mc.seed = 43;
  const std::vector<MachineMonteCarloRun> other = MachineMonteCarlo(layout, v, readings, {}, study.noise, Options(), mc);
  EXPECT_NE(one[0].final.mean_um(), other[0].final.mean_um());
}

TEST(MachineMonteCarlo, NoiseFreeTrackerGivesNoSpread) {
  const Study study;
  const ParameterLayout layout = Layout();
  const std::vector<Observation> readings = study.Readings(1);
  const VerificationResult v = VerifyMachine(layout, readings, Options());
  MonteCarloOptions mc;
  mc.runs = 3;
  mc.weighted = false;
  const std::vector<MachineMonteCarloRun> runs =
      MachineMonteCarlo(layout, v, readings, {}, TrackerNoise::Preset("none"), Options(), mc);
  // Every run reads the same truth exactly, so all agree (their common offset from the weighted reference is the
  // unweighted fit's, not a spread).
  for (const PointSpread& s : PointSpreads(runs)) EXPECT_LT(std::sqrt(s.covariance.trace()), 1e-6);
}

// The microscope stage: independent centre noise on the same simulated stage (the bundled sample's kind of batch),
// each identified with model 27, against the Monte Carlo from one of them.
TEST(StageMonteCarlo, PredictsTheSpreadOfIndependentMeasurements) {
  // Copies are drawn about F(q) (no first-tile frame), so the held-out exports leave the turn out as well.
  artefacts::FvmBatchOptions batch;
  batch.stitched_frame = StitchedFrame::kTranslated;
  const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(batch);
  const MeasurementSet identify = artefacts::Observations(sim.batch, sim.batch.identify);
  const MeasurementSet validate = artefacts::Observations(sim.batch, sim.batch.validate);
  constexpr double kSigma = 0.5e-3;  // the simulation's centre noise, mm
  const ParameterLayout layout = FvmModelLayout("27");
  IdentificationOptions options;
  options.num_threads = 1;
  // The true stage's stitched centres of the identification placements (the batch is not anchored: same start).
  std::vector<Eigen::Vector3d> truth;
  for (const Observation& o : identify.observations) {
    truth.push_back(Predict(sim.truth.layout, sim.truth.values.data(), Eigen::Vector3d(o.command)));
  }
  constexpr int kReal = 20;
  std::vector<double> real_rms;
  std::vector<std::vector<Eigen::Vector3d>> real_predictions;
  std::optional<IdentificationResult> first;
  MeasurementSet first_set;
  for (int k = 0; k < kReal; ++k) {
    Random random(1000 + static_cast<std::uint64_t>(k));
    MeasurementSet set = identify;
    for (size_t i = 0; i < set.observations.size(); ++i) {
      const double nx = random.Normal(), ny = random.Normal(), nz = random.Normal();
      set.observations[i].measured = truth[i] + kSigma * Eigen::Vector3d(nx, ny, nz);
    }
    IdentificationResult r = Identify(layout, set.observations, options);
    real_rms.push_back(Validate(&r.calibration, validate.observations, validate.anchors).rms_mm * 1e3);
    std::vector<Eigen::Vector3d> p;
    for (const Observation& o : validate.observations) {
      p.push_back(Predict(r.calibration.layout, r.calibration.values.data(), Eigen::Vector3d(o.command),
                          &validate.anchors.at(static_cast<size_t>(o.group))));
    }
    real_predictions.push_back(p);
    if (k == 0) first.emplace(std::move(r)), first_set = set;
  }
  MonteCarloOptions mc;
  mc.runs = 40;
  mc.seed = 11;
  const std::vector<StageMonteCarloRun> runs = StageMonteCarlo(layout, *first, first_set, &validate, kSigma, options, mc);
  std::vector<double> mc_rms;
  for (const StageMonteCarloRun& r : runs) mc_rms.push_back(r.validation.rms_mm * 1e3);
  const SampleSummary real = SummarizeSample(real_rms), simulated = SummarizeSample(mc_rms);
  std::printf("validation rms: independent %.3f +- %.3f um, Monte Carlo %.3f +- %.3f um\n", real.mean, real.sd,
              simulated.mean, simulated.sd);
  // The validation centres carry their own noise (0.5 um per coordinate, about 0.87 um in 3D), which no
  // identification changes; the spread of the rms comes from the model's uncertainty on top of it.
  EXPECT_NEAR(simulated.mean, real.mean, 3 * real.sd + 0.05);
  EXPECT_NEAR(simulated.sd / real.sd, 1.0, 0.6);
  // Where the identifications place each validation centre.
  const std::vector<PointSpread> spreads = PointSpreads(runs);
  ASSERT_EQ(spreads.size(), validate.observations.size());
  double real_sum = 0, mc_sum = 0;
  for (size_t p = 0; p < spreads.size(); ++p) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& pr : real_predictions) mean += pr[p];
    mean /= kReal;
    for (const auto& pr : real_predictions) real_sum += (pr[p] - mean).squaredNorm() / (kReal - 1);
    mc_sum += spreads[p].covariance.trace();
  }
  const double real_sd = 1e3 * std::sqrt(real_sum / spreads.size()), mc_sd = 1e3 * std::sqrt(mc_sum / spreads.size());
  std::printf("prediction spread at the validation centres: independent %.3f um, Monte Carlo %.3f um\n", real_sd, mc_sd);
  EXPECT_NEAR(mc_sd / real_sd, 1.0, 0.3);
}

// The [ISO/TS 15530-3] budget: u_p from the spreads, u_b from repeated commands (or the noise model), u_w from the
// temperature range and CTE, U = k sqrt(sum of squares).
TEST(UncertaintyBudget, CombinesItsFourContributions) {
  PointSpread a, b;
  a.covariance = Eigen::Vector3d(9e-6, 0, 0).asDiagonal();   // 3 um along x
  b.covariance = Eigen::Vector3d(0, 16e-6, 9e-6).asDiagonal();  // 5 um in y and z together
  std::vector<Observation> readings(4);
  readings[0].command = Eigen::Vector3d(0, 0, 0);
  readings[1].command = Eigen::Vector3d(0, 0, 0);
  readings[1].measured = Eigen::Vector3d(0.002, 0, 0);  // a repeat, 2 um away
  readings[2].command = Eigen::Vector3d(300, 400, 0);
  readings[3].command = Eigen::Vector3d(300, 400, 0);
  readings[3].tool = 1;                                  // another tool: not a repeat
  BudgetInputs inputs;
  inputs.u_cal_mm = 1e-3;
  inputs.temperature_half_range_k = 0.2;
  inputs.cte_per_k = 24e-6;
  const UncertaintyBudget budget = Budget({a, b}, readings, 0.05, inputs);
  EXPECT_NEAR(budget.u_p_mm, 2 * std::sqrt((9e-6 + 25e-6) / 2), 1e-12);
  EXPECT_EQ(budget.repeated_commands, 1);
  EXPECT_NEAR(budget.u_b_mm, std::sqrt(2e-6) / std::sqrt(2.0), 1e-12);  // s = sqrt(2 (1 um)^2 / 1), n = 2
  EXPECT_DOUBLE_EQ(budget.length_mm, 500.0);
  EXPECT_NEAR(budget.u_w_mm, 24e-6 * 500 * 0.2 / std::sqrt(3.0), 1e-15);
  EXPECT_NEAR(budget.U_mm, 2 * std::hypot(std::hypot(1e-3, budget.u_p_mm), std::hypot(budget.u_b_mm, budget.u_w_mm)), 1e-15);
  // Without repeats, one reading's standard deviation under the noise model.
  readings.resize(1);
  EXPECT_DOUBLE_EQ(Budget({a}, readings, 0.05, inputs).u_b_mm, 0.05);
}

TEST(MachineMonteCarlo, SummaryQuantiles) {
  const SampleSummary s = SummarizeSample({4, 1, 3, 2, 5});
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.sd, std::sqrt(2.5));
  EXPECT_DOUBLE_EQ(s.p95, 4.8);
  EXPECT_DOUBLE_EQ(s.max, 5.0);
}

}  // namespace
}  // namespace fvm::stage
