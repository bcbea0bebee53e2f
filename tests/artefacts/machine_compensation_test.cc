// The machine model as `fvm verify -o` writes it and `fvm correct` uses it: it reads back exactly (tool offset
// included), its inverse reproduces the nominal points, and on a simulated machine whose errors no polynomial
// takes the compensated commands put the true tool point nearer the nominal one than the plain commands do.

#include <gtest/gtest.h>
#include <unistd.h>

#include <iostream>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>

#include "artefacts/simulation/machine_tool_simulation.h"
#include "artefacts/tracker_observations.h"
#include "stage/calibration.h"
#include "stage/io/calibration_file.h"
#include "stage/machine_verification.h"

namespace fvm::artefacts {
namespace {

const Workspace kWorkspace;  // 2500 x 1500 x 1200 mm, [IJSIMM 2016] section 5
const Eigen::Vector3d kTool(0, 0, 100);

stage::AxisChain Chain() {
  stage::AxisChain chain = stage::AxisChain::Parse("XFYZ");
  chain.tool_offset = kTool;
  chain.instrument = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(1100, -1000, 600), Eigen::Vector3d(63, 14, 35));
  return chain;
}

stage::ParameterLayout Layout(int order) {
  stage::AxisChain chain = Chain();
  chain.instrument.reset();
  return stage::MachineLayout(chain, {stage::Travel{0, 2500}, stage::Travel{0, 1500}, stage::Travel{0, 1200}},
                              stage::Basis::kLegendre, order);
}

// Where the true machine puts the tool point commanded to q (machine frame).
Eigen::Vector3d TrueToolPoint(const MachineTruth& truth, const Eigen::Vector3d& q) {
  stage::AxisChain chain = Chain();
  chain.instrument.reset();
  double e[stage::kNumErrorTerms];
  TermValuesAt(truth, q, e);
  return stage::ChainForward(chain, e, q);
}

// Mean distance between the reached points and the wanted ones after the best rigid fit of the one set onto the
// other: a rigid motion of the whole machine frame is what no tracker reading (and no part set-up) can tell.
double MeanAfterRigidFitUm(const std::vector<Eigen::Vector3d>& reached, const std::vector<Eigen::Vector3d>& wanted) {
  Eigen::Matrix3Xd a(3, reached.size()), b(3, wanted.size());
  for (size_t i = 0; i < reached.size(); ++i) a.col(static_cast<Eigen::Index>(i)) = reached[i], b.col(static_cast<Eigen::Index>(i)) = wanted[i];
  const Eigen::Matrix4d t = Eigen::umeyama(a, b, false);
  double sum = 0;
  for (size_t i = 0; i < reached.size(); ++i) {
    sum += (t.topLeftCorner<3, 3>() * reached[i] + t.topRightCorner<3, 1>() - wanted[i]).norm();
  }
  return 1e3 * sum / static_cast<double>(reached.size());
}

class MachineCompensation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    truth_ = RandomMachineTruth(Chain(), kWorkspace, 1);
    const stage::TrackerNoise noise = stage::TrackerNoise::Preset("published");
    const TrackerReadings readings =
        SimulateTrackerReadings(Chain(), truth_, PlanMesh(kWorkspace, Eigen::Vector3d(500, 500, 400)), noise, 1);
    stage::IdentificationOptions options;
    options.instrument = stage::InstrumentPose::kEstimated;
    options.num_threads = 1;
    const stage::VerificationResult v = stage::VerifyMachine(Layout(3), TrackerObservations(readings, &noise), options);
    // Through the file, as fvm verify -o and fvm correct do.
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("fvm_machine_compensation_" + std::to_string(::getpid()) + ".json");
    std::ofstream(path) << stage::CalibrationToJson(v.identified).dump(1);
    written_ = new stage::Calibration(v.identified.calibration);
    read_ = new stage::Calibration(stage::ReadCalibration(path));
    std::filesystem::remove(path);
  }
  static void TearDownTestSuite() {
    delete written_;
    delete read_;
  }
  static MachineTruth truth_;
  static stage::Calibration* written_;
  static stage::Calibration* read_;
};
MachineTruth MachineCompensation::truth_;
stage::Calibration* MachineCompensation::written_ = nullptr;
stage::Calibration* MachineCompensation::read_ = nullptr;

TEST_F(MachineCompensation, TheModelFileReadsBackWithItsToolOffset) {
  EXPECT_EQ(read_->layout.chain().tool_offset, kTool);
  EXPECT_EQ(read_->layout.chain().code, "XFYZ");
  EXPECT_EQ(read_->values, written_->values);
  EXPECT_EQ(read_->covariance, written_->covariance);
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1234.5, 678.9, 1000)}) {
    EXPECT_EQ(stage::Forward(read_->layout, read_->values, q), stage::Forward(written_->layout, written_->values, q));
  }
}

TEST_F(MachineCompensation, TheForwardModelTakesTheCommandsBackToTheNominalPoints) {
  const Eigen::Vector3d origin_error = stage::Forward(read_->layout, read_->values, Eigen::Vector3d::Zero()) - kTool;
  for (const PlannedPoint& p : PlanMesh(kWorkspace, Eigen::Vector3d(250, 250, 200))) {
    const stage::Compensation c = stage::CompensateCommand(*read_, p.nominal);
    ASSERT_TRUE(c.converged) << p.id;
    const Eigen::Vector3d back = stage::Forward(read_->layout, read_->values, c.command) - kTool - origin_error;
    EXPECT_LT((back - p.nominal).norm(), 1e-9) << p.id;
  }
  // The model's gauge: no correction at the axes' origin.
  EXPECT_LT(stage::CompensateCommand(*read_, Eigen::Vector3d::Zero()).command.norm(), 1e-9);
}

TEST_F(MachineCompensation, CompensatedCommandsLandNearerTheNominalPointsOnTheTrueMachine) {
  std::vector<Eigen::Vector3d> wanted, plain, compensated;
  for (const PlannedPoint& p : PlanMesh(kWorkspace, Eigen::Vector3d(250, 250, 200))) {  // not the fitted points
    wanted.push_back(p.nominal + kTool);
    plain.push_back(TrueToolPoint(truth_, p.nominal));
    compensated.push_back(TrueToolPoint(truth_, stage::CompensateCommand(*read_, p.nominal).command));
  }
  const double before = MeanAfterRigidFitUm(plain, wanted), after = MeanAfterRigidFitUm(compensated, wanted);
  std::cout << "mean volumetric error on 539 unseen points (rigid fit removed): " << before << " um plain, " << after
            << " um compensated\n";
  // Measured: 16.1 um plain, 11.8 um compensated. What is left is the order-3 model's miss of the ball-screw and
  // long-wave errors and the 24 urad tracker noise (50-70 um across the beam at 2-3 m) on 96 readings: the same as
  // fvm verify's validation, 28.4 -> 16.5 um.
  EXPECT_GT(before, 10.0);
  EXPECT_LT(after, 0.8 * before);
}

}  // namespace
}  // namespace fvm::artefacts
