#include "workflows/uncertainty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "tests/support/test_support.h"
#include "artefacts/io/batch.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"
#include "core/random.h"
#include "stage/monte_carlo.h"
#include "tests/workflows/simulated_machine.h"
#include "workflows/tracker_placement.h"

namespace fvm::workflows {
namespace {

MachineProblem Problem(const testing::SimulatedMachine& m, const std::filesystem::path& dir, const std::string& tracker = "adm") {
  artefacts::WriteTrackerReadings(dir / "readings.csv", m.readings);
  MachineProblemOptions o;
  o.data = (dir / "readings.csv").string();
  o.tools = {Eigen::Vector3d(0, 0, 100)};
  o.tracker = tracker;
  return LoadMachineProblem(o);
}

double Mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

// The Monte Carlo against the covariance propagation written independently in stage (J (J^T W J)^+ J^T): each
// point's 95 % radius from 40 runs has a relative sampling error of about 10 %; averaged over 60 points (correlated)
// the two agree within 15 %. The same seed gives the same bits with 1 or 2 threads ([GUM Supplement 1] runs that
// a reader can repeat).
TEST(MachineUncertainty, AgreesWithCovariancePropagationAndRepeatsBitForBit) {
  const testing::SimulatedMachine m = testing::SimulateMachine(31, 300.0);
  fvm::testing::TempDir dir;
  const MachineProblem problem = Problem(m, dir.path());
  const MachineReference reference = IdentifyMachineReference(problem, 2);
  MonteCarloSettings settings;
  settings.runs = 40;
  settings.seed = 5;
  settings.threads = 2;
  const MachineUncertainty u = RunMachineMonteCarlo(problem, reference, settings, stage::BudgetInputs{});
  EXPECT_EQ(u.converged, 40);
  ASSERT_EQ(u.spreads.size(), problem.observations.size());
  const stage::Calibration& cal = reference.verification.identified.calibration;
  std::vector<double> monte_carlo, propagated;
  const auto covariances = stage::PredictedPointCovariances(cal, reference.verification.identified.pose, true,
                                                            problem.observations, problem.options.tool_offsets, problem.noise);
  for (size_t i = 0; i < covariances.size(); ++i) {
    monte_carlo.push_back(u.spreads[i].u95_mm);
    propagated.push_back(stage::U95OfCovariance(covariances[i]));
  }
  EXPECT_NEAR(Mean(monte_carlo) / Mean(propagated), 1.0, 0.15);
  // The budget's u_p is 2 x the rms of the points' 3-D standard deviation: positive and of the spread's size.
  EXPECT_GT(u.budget.U_mm, 0.0);

  settings.threads = 1;
  const MachineUncertainty again = RunMachineMonteCarlo(problem, reference, settings, stage::BudgetInputs{});
  EXPECT_EQ(again.final_mean_um, u.final_mean_um);
  EXPECT_EQ(again.model_error_pooled_um, u.model_error_pooled_um);
}

TEST(MachineUncertainty, ANoiseFreeTrackerIsRefused) {
  const testing::SimulatedMachine m = testing::SimulateMachine(32, 300.0);
  fvm::testing::TempDir dir;
  EXPECT_THROW(IdentifyMachineReference(Problem(m, dir.path(), "none"), 2), InputError);
}

// Readings that carry their own covariances (fvm multilaterate --verify-readings) are drawn from them: with
// --tracker none the Monte Carlo runs; the budget's one-reading sd is the covariances' (3 um per coordinate:
// sqrt(3) x 3 um), and the runs' spread is what 3 um of noise leaves: above zero, below one reading's 5.2 um.
TEST(MachineUncertainty, ReadingsWithTheirOwnCovariancesAreDrawnFromThem) {
  testing::SimulatedMachine m = testing::SimulateMachine(33, 300.0);
  Random random(7);
  for (size_t i = 0; i < m.readings.points.size(); ++i) {
    const double a = random.Normal(), b = random.Normal(), c = random.Normal();
    m.readings.points[i].measured = m.noise_free.points[i].measured + 0.003 * Eigen::Vector3d(a, b, c);
    m.readings.points[i].covariance = 9e-6 * Eigen::Matrix3d::Identity();
  }
  fvm::testing::TempDir dir;
  const MachineProblem problem = Problem(m, dir.path(), "none");
  const MachineReference reference = IdentifyMachineReference(problem, 2);
  MonteCarloSettings settings;
  settings.runs = 20;
  settings.seed = 3;
  const MachineUncertainty u = RunMachineMonteCarlo(problem, reference, settings, stage::BudgetInputs{});
  EXPECT_EQ(u.converged, 20);
  EXPECT_NEAR(u.budget.u_b_mm, std::sqrt(27e-6), 1e-12);
  double trace = 0;
  for (size_t i = 0; i < problem.observations.size(); ++i) trace += u.spreads[i].covariance.trace();
  const double sd_mm = std::sqrt(trace / static_cast<double>(problem.observations.size()));
  EXPECT_GT(sd_mm, 0.3e-3);
  EXPECT_LT(sd_mm, std::sqrt(27e-6));
}

// The stage: a simulated batch (0.5 um per coordinate, model 15) drawn again around its calibration. The
// validation rms over the runs is what fvm calibrate predicts from the covariance; 30 runs give its mean to about
// 1 %, the prediction is linear: within 10 %. The noise the runs draw is the fit's own residual sigma: 0.5 um in
// each of the two exports, sqrt(2) x 0.5 = 0.71 um per coordinate, a little more for the share the fit takes.
TEST(StageUncertainty, ValidationRmsOverTheRunsIsThePredictedOne) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 4;
  sim.truth_model = "15";
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  fvm::testing::TempDir dir;
  artefacts::WriteBatch(dir.path() / "batch", batch.batch);
  StageUncertaintyOptions options;
  options.batch = (dir.path() / "batch").string();
  options.model = {"15", ""};
  const StageReference reference = IdentifyStageReference(options);
  EXPECT_NEAR(reference.sigma_mm * 1e3, 0.5 * std::sqrt(2.0), 0.1);
  ASSERT_TRUE(reference.validate.has_value());
  MonteCarloSettings settings;
  settings.runs = 30;
  settings.seed = 2;
  const StageUncertainty u = RunStageMonteCarlo(options, reference, settings, stage::BudgetInputs{});
  EXPECT_EQ(u.converged, 30);
  ASSERT_TRUE(u.validation.has_value());
  EXPECT_NEAR(Mean(u.validation_rms_um) / (u.validation->predicted_rms_mm * 1e3), 1.0, 0.1);
  EXPECT_EQ(u.spreads.size(), reference.validate->observations.size());
}

// Placement: the position ranked best by the propagation is confirmed by the Monte Carlo to be no worse than the
// readings' own tracker (30 runs: the largest radius over the points to about 10 %), and the propagation's figure
// for each confirmed position is the Monte Carlo's within 25 %.
TEST(TrackerPlacement, PicksAPositionNoWorseThanTheReadingsOwn) {
  const testing::SimulatedMachine m = testing::SimulateMachine(33, 300.0);
  fvm::testing::TempDir dir;
  const MachineProblem problem = Problem(m, dir.path());
  const MachineReference reference = IdentifyMachineReference(problem, 1);
  TrackerPlacementOptions options;
  options.box = {-600, -1400, 0, 1600, -800, 900};
  options.box_name = "box";
  options.steps = 2;
  options.confirm = 1;
  options.monte_carlo.runs = 30;
  int positions = 0;
  options.on_position_done = [&positions] { ++positions; };
  const TrackerPlacement placed = PlaceTracker(problem, reference, options);
  EXPECT_EQ(positions, PlacementPositions(options));
  EXPECT_EQ(placed.candidates, 8u);
  ASSERT_FALSE(placed.ranked.empty());
  const PlacementCandidate& best = placed.ranked.front();
  const auto own = std::find_if(placed.ranked.begin(), placed.ranked.end(), [](const auto& c) { return c.current; });
  ASSERT_NE(own, placed.ranked.end());
  ASSERT_GE(best.monte_carlo_max_um, 0.0);
  ASSERT_GE(own->monte_carlo_max_um, 0.0);
  EXPECT_LE(best.monte_carlo_max_um, 1.1 * own->monte_carlo_max_um);
  for (const PlacementCandidate& c : {best, *own}) EXPECT_NEAR(c.monte_carlo_max_um / c.predicted_max_um, 1.0, 0.25);
}

TEST(TrackerPlacement, ABoxNoPositionOfWhichSeesEveryPointIsRefusedNamingIt) {
  const testing::SimulatedMachine m = testing::SimulateMachine(34, 300.0);
  fvm::testing::TempDir dir;
  const MachineProblem problem = Problem(m, dir.path());
  const MachineReference reference = IdentifyMachineReference(problem, 1);
  TrackerPlacementOptions options;
  options.box = {400, 300, 5000, 600, 500, 6000};  // straight above the machine: the points below -60 deg
  options.box_name = "--place-tracker 400,300,5000,600,500,6000";
  options.steps = 2;
  try {
    PlaceTracker(problem, reference, options);
    FAIL() << "a box without a position that sees the points was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(options.box_name + ": from no position of the box", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace fvm::workflows
