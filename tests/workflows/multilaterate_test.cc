#include "workflows/multilaterate.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <fstream>

#include "tests/support/test_support.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "core/file_io.h"
#include "core/number_text.h"
#include "tests/workflows/simulated_machine.h"
#include "workflows/machine_problem.h"

namespace fvm::workflows {
namespace {

// Four levelled stations around the 1000 x 800 x 600 mm workspace, at different heights, read with an absolute
// distance meter's noise; the points are the workspace's mesh with 250 mm steps (100 points).
struct Network {
  fvm::testing::TempDir dir;
  std::vector<std::pair<std::string, Eigen::Vector3d>> targets;
  MultilaterateOptions options;

  Network() {
    const std::vector<artefacts::Station> stations{{"A", {-800, -700, 900}},
                                                   {"B", {1900, -600, 200}},
                                                   {"C", {1800, 1600, 1000}},
                                                   {"D", {-700, 1500, 100}}};
    for (const artefacts::PlannedPoint& p : artefacts::PlanMesh(testing::TestWorkspace(), Eigen::Vector3d::Constant(250))) {
      targets.emplace_back(p.id, p.nominal);
    }
    const auto readings =
        artefacts::SimulateMultilaterationReadings(stations, targets, {}, stage::TrackerNoise::Preset("adm"), 21);
    artefacts::WriteMultilaterationReadings(dir.path() / "readings.csv", readings);
    WriteFileAtomically(dir.path() / "stations.json", artefacts::StationsJson(stations));
    std::ofstream truth(dir.path() / "true_points.csv");
    truth << "id,x,y,z\n";
    for (const auto& [id, p] : targets) {
      truth << id << ',' << FormatShortest(p.x()) << ',' << FormatShortest(p.y()) << ',' << FormatShortest(p.z()) << '\n';
    }
    options.readings = (dir.path() / "readings.csv").string();
    options.stations = (dir.path() / "stations.json").string();
    options.tracker = "adm";
  }
};

// Known stations, ranges only: each point's error against the truth, weighed by the covariance the job states for
// it, is chi-square with 3 degrees of freedom: mean 3, variance 6. Over 100 points the mean has a standard deviation
// of sqrt(6 / 100) = 0.24; 2.0-4.0 is 4 sigma. The truth error the job reports is the one written out here.
TEST(Multilaterate, RecoversSimulatedPointsWithinTheirCovariance) {
  const Network net;
  const Multilateration m = Multilaterate(net.options);
  ASSERT_TRUE(m.result.converged);
  ASSERT_EQ(m.result.points.size(), net.targets.size());
  EXPECT_EQ(m.Mode(), "ranges only");
  double chi2 = 0, sum = 0, worst = 0;
  for (size_t j = 0; j < net.targets.size(); ++j) {
    ASSERT_EQ(m.problem.point_ids[j], net.targets[j].first);
    const Eigen::Vector3d d = m.result.points[j] - net.targets[j].second;
    chi2 += d.dot(m.result.point_covariance[j].ldlt().solve(d));
    sum += d.norm();
    worst = std::max(worst, d.norm());
  }
  const double n = static_cast<double>(net.targets.size());
  EXPECT_GT(chi2 / n, 2.0);
  EXPECT_LT(chi2 / n, 4.0);
  const stage::ResidualSummary e = ErrorAgainstTruth(m, (net.dir.path() / "true_points.csv").string());
  EXPECT_NEAR(e.mean_mm, sum / n, 1e-12);
  EXPECT_NEAR(e.max_mm, worst, 1e-12);
  // The stated uncertainty is the one the points show: mean |u| within 20 % of the rms error (sd of the rms of
  // 100 3-D errors about 5 %).
  EXPECT_NEAR(e.rms_mm / m.u_mean_mm, 1.0, 0.2);
}

// The points as readings for a verification carry the nominal coordinates of --nominal, ids in file order.
TEST(Multilaterate, WritesThePointsAsReadingsForVerificationWithTheirNominalCoordinates) {
  const Network net;
  const Multilateration m = Multilaterate(net.options);
  const std::string nominal_file = (net.dir.path() / "true_points.csv").string();
  const auto nominal = NominalCoordinates(m, nominal_file);
  const artefacts::TrackerReadings r = VerifyReadings(m, net.options, nominal, nominal_file, "ml.csv");
  ASSERT_EQ(r.points.size(), net.targets.size());
  EXPECT_EQ(r.points[7].id, net.targets[7].first);
  EXPECT_EQ(r.points[7].nominal, net.targets[7].second);
  EXPECT_EQ(r.points[7].measured, m.result.points[7]);
  // Each point carries its covariance, and a verification weighs it by that, not by one tracker's noise model.
  ASSERT_TRUE(r.points[7].covariance.has_value());
  EXPECT_EQ(*r.points[7].covariance, m.result.point_covariance[7]);
  MachineProblemOptions verify;
  verify.tools = {Eigen::Vector3d(0, 0, 100)};
  verify.tracker = "none";
  const MachineProblem problem = MakeMachineProblem(verify, r, std::nullopt);
  EXPECT_TRUE(problem.weighted);
  EXPECT_EQ(problem.WeightsName(), "the readings' covariances");
  EXPECT_EQ(problem.observations[7].covariance, m.result.point_covariance[7]);
  verify.unweighted = true;
  EXPECT_EQ(MakeMachineProblem(verify, r, std::nullopt).observations[7].covariance, Eigen::Matrix3d::Zero());
  try {
    VerifyReadings(m, net.options, {}, "", "ml.csv");
    FAIL() << "readings for verification without nominal coordinates were made";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--verify-readings ml.csv: needs each point's nominal"), std::string::npos)
        << e.what();
  }
}

TEST(Multilaterate, AStationWithoutReadingsIsRefusedNamingTheStationsFile) {
  Network net;
  std::vector<artefacts::Station> stations = artefacts::ReadStations(net.options.stations);
  stations.push_back({"E", {500, 400, 2000}});
  WriteFileAtomically(net.options.stations, artefacts::StationsJson(stations));
  try {
    Multilaterate(net.options);
    FAIL() << "a station without readings was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), net.options.stations + ": station E has no readings in " + net.options.readings +
                                         "; remove it or add its readings");
  }
}

}  // namespace
}  // namespace fvm::workflows
