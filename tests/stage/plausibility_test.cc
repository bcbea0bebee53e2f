// Plausibility of identified machines and multilateration networks (issue 35): results no machine or network can
// have are refused with the reason, on readings written out here from the ideal chain (no fvm simulation), while a
// machine with errors of 0.1 mm per metre and the rigid pose of [IJSIMM 2016] passes with a wide margin.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "stage/machine_verification.h"
#include "stage/multilateration.h"
#include "stage/network_plausibility.h"
#include "stage/plausibility.h"

namespace fvm::stage {
namespace {

const Eigen::Vector3d kTravel(2500.0, 1500.0, 1200.0);  // [IJSIMM 2016] Table I

// A tracker at 1100, -1000, 600 mm turned by 30 deg about z; a point's reading is R^T (p - t).
Pose TrackerPose() {
  Pose pose;
  pose.translation = Eigen::Vector3d(1100.0, -1000.0, 600.0);
  pose.rotation = Eigen::Vector3d(0.0, 0.0, 30.0 * M_PI / 180.0);
  return pose;
}

AxisChain Chain() {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0.0, 0.0, 100.0);
  return chain;
}

// A 5 x 4 x 4 mesh of readings of a machine whose positioning errs by `scale` per unit of travel on every axis.
std::vector<Observation> Readings(double scale) {
  const Pose pose = TrackerPose();
  const Eigen::Matrix3d r = pose.Rotation();
  const double zero[kNumErrorTerms] = {};
  std::vector<Observation> out;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 4; ++j) {
      for (int k = 0; k < 4; ++k) {
        Observation o;
        o.command = Eigen::Vector3d(kTravel.x() * i / 4, kTravel.y() * j / 3, kTravel.z() * k / 3);
        const Eigen::Vector3d p = ChainForward(Chain(), zero, o.command) + scale * o.command;
        o.measured = r.transpose() * (p - pose.translation);
        out.push_back(o);
      }
    }
  }
  return out;
}

ParameterLayout Layout() {
  std::array<Travel, 3> travel;
  for (int k = 0; k < 3; ++k) travel[static_cast<size_t>(k)] = Travel{0.0, kTravel[k]};
  return MachineLayout(Chain(), travel, Basis::kLegendre, 2);
}

IdentificationOptions Estimated() {
  IdentificationOptions o;
  o.instrument = InstrumentPose::kEstimated;
  return o;
}

std::string RefusalOf(const std::vector<Observation>& readings, const IdentificationOptions& options) {
  try {
    VerifyMachine(Layout(), readings, options);
  } catch (const ImplausibleFit& e) {
    return e.what();
  }
  return "";
}

TEST(Plausibility, DefaultBoundIsOneMillimetrePerMetreOfTheLongestTravel) {
  EXPECT_DOUBLE_EQ(DefaultMaxErrorMm(Layout()), 2.5);
}

TEST(Plausibility, AMachineWithinItsBoundPasses) {
  // 0.1 mm per metre on every axis: 0.25 mm over X, a tenth of the bound.
  const VerificationResult v = VerifyMachine(Layout(), Readings(1e-4), Estimated());
  const TermExcess largest = LargestExcess(v.identified.calibration, 2.5);
  EXPECT_NEAR(largest.share, 0.1, 0.01);
  EXPECT_EQ(std::string(GetErrorTerm(largest.term).vdi), "xTx");
  EXPECT_NEAR(std::abs(largest.slope), 1e-4, 1e-6);  // the sign is the chain's (X moves the part)
}

TEST(Plausibility, AMirroredAxisIsNamed) {
  std::vector<Observation> mirrored = Readings(0.0);
  // Mirror the machine's z in the tracker frame: reflect the readings across the tracker's xy plane after undoing
  // nothing else. The pose turns about z only, so the machine's z is the tracker's z.
  for (Observation& o : mirrored) o.measured.z() = -o.measured.z();
  const std::string why = RefusalOf(mirrored, Estimated());
  EXPECT_NE(why.find("zTz"), std::string::npos) << why;
  EXPECT_NE(why.find("mirrored"), std::string::npos) << why;
  EXPECT_NE(why.find("bound 2.5 mm"), std::string::npos) << why;
  // The bound is the caller's: beyond the -2400 mm the fit needs, the same readings pass, explained by zTz.
  IdentificationOptions wide = Estimated();
  wide.max_error_mm = 3000.0;
  const VerificationResult v = VerifyMachine(Layout(), mirrored, wide);
  const TermExcess largest = LargestExcess(v.identified.calibration, 3000.0);
  EXPECT_EQ(std::string(GetErrorTerm(largest.term).vdi), "zTz");
  EXPECT_NEAR(largest.slope, -2.0, 1e-6);
}

TEST(Plausibility, IdenticalReadingsAreRankDeficient) {
  std::vector<Observation> same = Readings(0.0);
  for (Observation& o : same) o.measured = Eigen::Vector3d(100.0, 200.0, 300.0);
  const std::string why = RefusalOf(same, Estimated());
  EXPECT_NE(why.find("the same point"), std::string::npos) << why;
  EXPECT_NE(why.find("rank-deficient"), std::string::npos) << why;
  EXPECT_NE(why.find("pose_rx"), std::string::npos) << why;
  // A held pose does not make them a machine.
  IdentificationOptions held;
  held.instrument = InstrumentPose::kHeld;
  held.pose = TrackerPose();
  EXPECT_NE(RefusalOf(same, held).find("the same point"), std::string::npos);
  // Readings in a plane: the tracker's x column constant.
  std::vector<Observation> flat = Readings(0.0);
  for (Observation& o : flat) o.measured.x() = 5.0;
  EXPECT_NE(RefusalOf(flat, Estimated()).find("in a plane"), std::string::npos);
}

// Four stations at the corners of a 5 km tetrahedron.
MultilaterationProblem FarNetwork(double range_mm, int points) {
  MultilaterationProblem p;
  p.station_names = {"A", "B", "C", "D"};
  p.stations = {Eigen::Vector3d::Zero(), Eigen::Vector3d(5000, 0, 0), Eigen::Vector3d(0, 5000, 0), Eigen::Vector3d(0, 0, 5000)};
  for (int j = 0; j < points; ++j) {
    p.point_ids.push_back(std::to_string(j + 1));
    for (int i = 0; i < 4; ++i) p.readings.push_back({j, i, range_mm, false, 0.0, 0.0});
  }
  return p;
}

TEST(NetworkPlausibility, RangesThatDoNotMeetAreRefused) {
  MultilaterationOptions o;
  o.noise = TrackerNoise::Preset("published");
  try {
    Multilaterate(FarNetwork(1000.0, 1), o);
    FAIL() << "four ranges of 1 m to stations 5 km apart were accepted";
  } catch (const ImplausibleFit& e) {
    EXPECT_NE(std::string(e.what()).find("the ranges do not meet"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point 1,"), std::string::npos) << e.what();
  }
}

TEST(NetworkPlausibility, ACollapsedSelfCalibrationIsRefused) {
  MultilaterationOptions o;
  o.noise = TrackerNoise::Preset("published");
  o.self_calibrate = true;
  try {
    Multilaterate(FarNetwork(1e-6, 8), o);
    FAIL() << "stations collapsed onto one spot were accepted";
  } catch (const ImplausibleFit& e) {
    EXPECT_NE(std::string(e.what()).find("collapsed onto one spot"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fvm::stage
