#include "workflows/verify_machine.h"

#include <gtest/gtest.h>

#include "tests/support/test_support.h"
#include "stage/monte_carlo.h"
#include "tests/workflows/simulated_machine.h"

namespace fvm::workflows {
namespace {

MachineProblemOptions OptionsFor(const std::filesystem::path& readings) {
  MachineProblemOptions o;
  o.data = readings.string();
  o.tools = {Eigen::Vector3d(0, 0, 100)};
  o.tracker = "adm";
  return o;
}

// The job recovers a machine its model can take (cubic errors, order 3) down to the tracker's noise: the weighted
// residual is the noise model's (chi^2 per degree of freedom 1), and each reading the identified machine predicts
// lies within the 95 % radius that covariance propagation gives it of the noise-free truth. 100 points, 300
// equations, 60-odd free parameters: the weighted rms has a standard deviation of sqrt(1 / (2 dof)) = 0.05, so
// 0.85-1.15 is 3 sigma; 95 % of the points fall within their radius, 80 % leaves room for 100 correlated points.
TEST(VerifyMachine, RecoversASimulatedMachineWithinItsUncertainty) {
  const testing::SimulatedMachine m = testing::SimulateMachine(11);
  fvm::testing::TempDir dir;
  artefacts::WriteTrackerReadings(dir.path() / "readings.csv", m.readings);
  const MachineProblem problem = LoadMachineProblem(OptionsFor(dir.path() / "readings.csv"));
  EXPECT_EQ(problem.WeightsName(), "tracker adm");
  const MachineVerification v = VerifyMachine(problem, {.orders = {3}});
  ASSERT_EQ(v.fits.size(), 1u);
  const stage::VerificationResult& r = v.Chosen().result;
  ASSERT_TRUE(r.identified.converged);
  EXPECT_GT(r.identified.weighted_rms, 0.85);
  EXPECT_LT(r.identified.weighted_rms, 1.15);
  // Before: the machine (100 um mean) and the noise; after: the noise alone (about 15 um of 3-D reading error).
  EXPECT_GT(r.initial.mean_um(), 3 * r.final.mean_um());

  const stage::Calibration& cal = r.identified.calibration;
  const std::vector<Eigen::Vector3d> predicted = stage::PredictedReadings(
      cal.layout, &cal.values, r.identified.pose, problem.observations, problem.options.tool_offsets);
  const std::vector<Eigen::Matrix3d> covariances = stage::PredictedPointCovariances(
      cal, r.identified.pose, true, problem.observations, problem.options.tool_offsets, problem.noise);
  int within = 0;
  double worst_ratio = 0;
  for (size_t i = 0; i < predicted.size(); ++i) {
    const double error = (predicted[i] - m.noise_free.points[i].measured).norm();
    const double u95 = stage::U95OfCovariance(covariances[i]);
    within += error <= u95 ? 1 : 0;
    worst_ratio = std::max(worst_ratio, error / u95);
  }
  EXPECT_GE(within, static_cast<int>(0.8 * static_cast<double>(predicted.size())));
  EXPECT_LT(worst_ratio, 2.5);  // no point far outside: a wrong model would miss by many radii
}

// --order auto: the cubic machine needs order 3; without held-out points BIC says so, with them their mean error.
TEST(VerifyMachine, ChoosesTheOrderTheMachineNeeds) {
  const testing::SimulatedMachine m = testing::SimulateMachine(12, 250.0, 100.0, 400.0);
  const testing::SimulatedMachine held_out = testing::SimulateMachine(12, 200.0, 100.0, 400.0);
  fvm::testing::TempDir dir;
  artefacts::WriteTrackerReadings(dir.path() / "readings.csv", m.readings);
  artefacts::WriteTrackerReadings(dir.path() / "validation.csv", held_out.noise_free);
  MachineProblemOptions o = OptionsFor(dir.path() / "readings.csv");
  const MachineVerification by_bic = VerifyMachine(LoadMachineProblem(o), {.orders = {1, 2, 3}});
  EXPECT_EQ(by_bic.ChosenBy(), "BIC");
  EXPECT_EQ(by_bic.Chosen().order, 3);
  o.validate = (dir.path() / "validation.csv").string();
  const MachineVerification by_validation = VerifyMachine(LoadMachineProblem(o), {.orders = {1, 2, 3}});
  EXPECT_EQ(by_validation.ChosenBy(), "validation mean");
  EXPECT_EQ(by_validation.Chosen().order, 3);
  // The held-out points are noise-free: what is left on them is the model's own uncertainty, a few um.
  EXPECT_LT(by_validation.Chosen().validation->after.mean_um(), 0.2 * by_validation.Chosen().validation->before.mean_um());
}

TEST(VerifyMachine, ATravelThatMissesAPointIsRefusedNamingTheFileLineAndPoint) {
  const testing::SimulatedMachine m = testing::SimulateMachine(13);
  fvm::testing::TempDir dir;
  artefacts::WriteTrackerReadings(dir.path() / "readings.csv", m.readings);
  MachineProblemOptions o = OptionsFor(dir.path() / "readings.csv");
  o.travel = testing::TestWorkspace();
  o.travel->max.x() = 600;
  o.travel_name = "--machine '600x800x600'";
  try {
    LoadMachineProblem(o);
    FAIL() << "a point outside the travel was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("--machine '600x800x600': " + o.data + ":", 0), 0u) << what;
    EXPECT_NE(what.find("point P0004 has x = 750 mm, outside the declared X travel 0 .. 600 mm"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace fvm::workflows
