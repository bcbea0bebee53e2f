// The machine-tool jobs' summaries (workflows/*_summary.h) and options: what the --json, the printed lines and the
// report say is the result's own numbers, and each options struct refuses what no job takes, naming the option.

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/input_error.h"
#include "tests/workflows/simulated_machine.h"
#include "workflows/machine_problem.h"
#include "workflows/machined_piece_summary.h"
#include "workflows/simulate_testpiece.h"
#include "workflows/simulate_tracker.h"
#include "workflows/uncertainty_summary.h"
#include "workflows/verify_summary.h"

namespace fvm::workflows {
namespace {

// The problem of a simulated machine, verified at order 2; `pose` held when given.
struct Verified {
  MachineProblem problem;
  VerifyMachineOptions options;
  MachineVerification verification;
};
Verified VerifySimulated(std::optional<stage::Pose> pose = std::nullopt) {
  const testing::SimulatedMachine m = testing::SimulateMachine(5);
  Verified v;
  v.options.machine.tools = {m.chain.tool_offset};
  v.options.machine.pose = pose;
  v.options.orders = {2};
  v.problem = MakeMachineProblem(v.options.machine, m.readings, std::nullopt);
  v.verification = VerifyMachine(v.problem, v.options);
  return v;
}

TEST(VerifySummary, TheDocumentTextAndReportSayTheResultsNumbers) {
  const Verified v = VerifySimulated();
  const Summary s = Summarize(v.problem, v.options, v.verification, "machine.json");
  const stage::VerificationResult& r = v.verification.Chosen().result;
  EXPECT_EQ(s.json["order"], 2);
  EXPECT_EQ(s.json["points"], v.problem.readings.points.size());
  EXPECT_DOUBLE_EQ(s.json["final"]["mean_um"].get<double>(), r.final.mean_um());
  EXPECT_TRUE(s.json["pose"]["estimated"].get<bool>());
  EXPECT_TRUE(s.json["pose"].contains("u_translation_um"));  // estimated: with its uncertainty
  EXPECT_DOUBLE_EQ(s.json["pose"]["translation_mm"][0].get<double>(), r.identified.pose.translation.x());
  EXPECT_NE(s.text.find(fmt::format("final max {:.1f} / mean {:.1f}", r.final.max_um(), r.final.mean_um())), std::string::npos);
  EXPECT_NE(s.text.find("; model written to machine.json\n"), std::string::npos);
  ASSERT_TRUE(s.report.has_value());
  const auto& page = std::get<report::MachineReportData>(*s.report);
  EXPECT_EQ(page.readings.size(), v.problem.readings.points.size());
  EXPECT_EQ(page.title, "fvm verify: XFYZ order 2 (legendre) on simulated");
  // The machine file: the calibration with the pose and the errors; the front end adds the data's path.
  const nlohmann::json model = MachineModelJson(v.problem, v.options, v.verification);
  EXPECT_EQ(model["model"], "machine XFYZ legendre order 2");
  EXPECT_EQ(model["instrument_pose"], s.json["pose"]);
}

TEST(VerifySummary, AHeldPoseHasNoUncertaintyAndSaysHeld) {
  const testing::SimulatedMachine m = testing::SimulateMachine(5);
  const Verified v = VerifySimulated(*m.chain.instrument);
  const Summary s = Summarize(v.problem, v.options, v.verification);
  EXPECT_FALSE(s.json["pose"]["estimated"].get<bool>());
  EXPECT_FALSE(s.json["pose"].contains("u_translation_um"));
  EXPECT_NE(s.text.find("tracker pose (held)"), std::string::npos);
  EXPECT_EQ(s.text.find("model written"), std::string::npos);
}

TEST(MachineOptions, ChecksNameTheOptions) {
  MachineProblemOptions o;
  EXPECT_NO_THROW(o.Check());
  o.basis = "fourier";
  EXPECT_THROW(
      try { o.Check(); } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--basis fourier"), std::string::npos);
        throw;
      },
      InputError);
  o = MachineProblemOptions();
  o.tracker = "laser";
  EXPECT_THROW(o.Check(), InputError);
  o = MachineProblemOptions();
  o.tools.clear();
  EXPECT_THROW(o.Check(), InputError);
  VerifyMachineOptions v;
  v.orders = {4};
  EXPECT_THROW(v.Check(), InputError);
  EXPECT_EQ(ParseOrders("auto"), (std::vector<int>{1, 2, 3}));
  EXPECT_THROW(ParseOrders("4"), InputError);
  UncertaintyOptions u;
  EXPECT_NO_THROW(u.Check());
  u.monte_carlo.runs = 0;
  EXPECT_THROW(u.Check(), InputError);
  MachinedPieceVerifyOptions piece;
  EXPECT_EQ(piece.machine.basis, "chebyshev");  // the CMM's defaults
  EXPECT_TRUE(piece.machine.unweighted);
  piece.order = 0;
  EXPECT_THROW(piece.Check(), InputError);
}

// The same seed gives the same bytes; a plan without a truth has no readings; every part of the simulation draws
// from its own seed, so a validation cloud changes nothing of the readings.
TEST(SimulateTracker, SameSeedSameBytesAndIndependentParts) {
  SimulateTrackerOptions o;
  o.machine.max = Eigen::Vector3d(1000, 800, 600);
  o.points.step = Eigen::Vector3d(250, 200, 200);
  o.pose_mm = Eigen::Vector3d(500, -1500, 300);
  o.pose_euler_deg = Eigen::Vector3d(0, 0, 0);
  const SimulatedTracker plan = SimulateTracker(o);
  EXPECT_FALSE(plan.readings.has_value());
  EXPECT_FALSE(plan.truth.has_value());
  o.seed = 7;
  const SimulatedTracker a = SimulateTracker(o), b = SimulateTracker(o);
  ASSERT_TRUE(a.readings.has_value());
  EXPECT_EQ(a.truth->dump(), b.truth->dump());
  EXPECT_EQ(a.readings->points.front().measured, b.readings->points.front().measured);
  EXPECT_EQ(a.points_csv, plan.points_csv);  // a mesh does not depend on the seed
  o.validation = PointPlan{"cloud", Eigen::Vector3d(300, 300, 300), 0};
  const SimulatedTracker c = SimulateTracker(o);
  EXPECT_EQ(c.readings->points.back().measured, a.readings->points.back().measured);
  ASSERT_TRUE(c.validation.has_value());
  EXPECT_EQ(c.validation->points.front().id[0], 'V');
  EXPECT_GT((*c.truth)["mean_error_um"].get<double>(), 10.0);  // the random machine's 35 um, on these points
  o.seed.reset();
  EXPECT_THROW(o.Check(), InputError);  // a validation needs a truth
}

TEST(SimulateTestPiece, TheProposedSeriesAddThreeToolsAndTheirPoints) {
  SimulateTestPieceOptions o;
  o.points = "series";
  const SimulatedTestPiece plain = SimulateTestPiece(o);
  o.proposed_series = true;
  const SimulatedTestPiece proposed = SimulateTestPiece(o);
  EXPECT_EQ(proposed.tools.size(), 4u);
  EXPECT_EQ(proposed.measured.points.size(), 4 * plain.measured.points.size());
  EXPECT_EQ(proposed.measured.points.back().tool, 3);
  const Summary s = Summarize(proposed, o, "tp");
  EXPECT_NE(s.text.find("verify with --tool 0,0,100 --tool 30,0,100 --tool -30,0,100 --tool 0,0,150"), std::string::npos);
  EXPECT_EQ(s.json["errors"], "[Lorente 2021] Table 4");
  o.points = "some";
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace fvm::workflows
