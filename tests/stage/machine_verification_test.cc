// Volumetric verification of an XFYZ machine with a laser tracker, checked against data and a fit that share none
// of fvm's kinematics: the readings come from [Aguado 2016] eq. 1 written out (last term X) with error
// functions that no polynomial can take (ball-screw-like sines on top of cubics), and the reference fit is a
// separately written Gauss-Newton on the same equation with numeric derivatives.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "stage/machine_verification.h"
#include "stage/tracker.h"
#include "tests/stage/written_out_machine.h"

namespace fvm::stage {
namespace {

using testing::Errors;
using testing::Estimated;
using testing::kTool;
using testing::kWorkspace;
using testing::MachineLayout;
using testing::MakeTruth;
using testing::Mesh;
using testing::Readings;
using testing::SeedReading;
using testing::SmallRotation;
using testing::Tracker;
using testing::Truth;

TEST(MachineVerification, RecoversAPolynomialMachineAndTheTrackerPoseWithoutNoise) {
  const Truth truth = MakeTruth(3, true);
  const Tracker tracker;
  const std::vector<Observation> readings = Readings(truth, Mesh({500, 500, 400}), tracker, nullptr, 0);
  ASSERT_EQ(readings.size(), 96u);  // the [IJSIMM 2016] mesh
  const VerificationResult r = VerifyMachine(MachineLayout(Basis::kPower, 3), readings, Estimated());
  EXPECT_GT(r.initial.mean_um(), 10.0);
  // Small-angle inverse and products of errors are in both models alike: what is left is rounding.
  EXPECT_LT(r.final.max_um(), 1e-3);
  const std::vector<Observation> unseen = Readings(truth, Mesh({250, 250, 200}), tracker, nullptr, 0);
  EXPECT_LT(Summarize(VolumetricResiduals(r.identified.calibration.layout, &r.identified.calibration.values,
                                                    r.identified.pose, unseen)).max_um(), 1e-3);
  // The constant terms cannot be told from the pose: they are fixed and say so.
  int absorbed = 0;
  for (const FixedCoefficient& f : r.identified.fixed) absorbed += f.reason.find("pose") != std::string::npos;
  EXPECT_GE(absorbed, 6);
}

TEST(MachineVerification, ASecondToolOffsetMakesMoreTermsIdentifiable) {
  const Truth truth = MakeTruth(4, true);
  const Tracker tracker;
  const std::vector<Observation> one = Readings(truth, Mesh({500, 500, 400}), tracker, nullptr, 0);
  const VerificationResult single = VerifyMachine(MachineLayout(Basis::kPower, 3), one, Estimated());
  // A second tool offset (x and y lever arms) on the same points.
  IdentificationOptions two_tools = Estimated();
  two_tools.tool_offsets = {kTool, Eigen::Vector3d(150.0, 80.0, 100.0)};
  std::vector<Observation> both = one;
  for (Observation o : one) {
    o.tool = 1;
    // The second tool's readings from [Aguado 2016] eq. 1 with its own offset.
    const Errors e = truth.At(o.command);
    const Eigen::Vector3d t2 = two_tools.tool_offsets[1];
    const Eigen::Vector3d xv(-o.command.x() + e.x_t.x(), e.x_t.y(), e.x_t.z());
    const Eigen::Vector3d yv(e.y_t.x() - o.command.y() * e.xwy, o.command.y() + e.y_t.y(), e.y_t.z());
    const Eigen::Vector3d zv(e.z_t.x() - o.command.z() * e.xwz, e.z_t.y() - o.command.z() * e.ywz, o.command.z() + e.z_t.z());
    const Eigen::Vector3d part = SmallRotation(e.x_r).inverse() * (SmallRotation(e.y_r) * (SmallRotation(e.z_r) * t2 + zv) + yv - xv);
    o.measured = tracker.rotation.transpose() * (part - tracker.translation);
    both.push_back(o);
  }
  const VerificationResult dual = VerifyMachine(MachineLayout(Basis::kPower, 3), both, two_tools);
  EXPECT_LT(dual.identified.fixed.size(), single.identified.fixed.size());
  EXPECT_LT(dual.final.max_um(), 1e-3);
  // Named reasons: with the tool offset in z only, ex(z) and ey(z) act only through it.
  bool zrx_named = false;
  for (const FixedCoefficient& f : single.identified.fixed) zrx_named |= f.name.rfind("zR", 0) == 0;
  EXPECT_TRUE(zrx_named);
}

// Any three-axis F-notation chain: FXYZ (all axes move the tool) and XYFZ (two move the part), simulated with the
// library's chain (the XFYZ tests above check that chain against [Aguado 2016] eq. 1) and a polynomial truth.
TEST(MachineVerification, OtherChainsRecoverTheirMachineWithoutNoise) {
  for (const char* code : {"FXYZ", "XYFZ"}) {
    AxisChain chain = AxisChain::Parse(code);
    chain.tool_offset = kTool;
    ParameterLayout layout(chain, {Travel{0, kWorkspace.x()}, Travel{0, kWorkspace.y()}, Travel{0, kWorkspace.z()}});
    for (const char* axis : {"x", "y", "z"}) {
      for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"}) layout.SetTerm(std::string(axis) + kind, Basis::kLegendre, 2);
    }
    for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, Basis::kLegendre, 0);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<double> truth;
    for (const std::string& name : layout.FreeNames()) {
      const bool translation = name[1] == 'T';
      truth.push_back(unit(rng) * (translation ? 0.01 : 2e-5));
    }
    const Tracker tracker;
    const Eigen::AngleAxisd angle_axis(tracker.rotation);
    double posed[6];  // translation, rotation vector
    for (int k = 0; k < 3; ++k) {
      posed[k] = tracker.translation[k];
      posed[3 + k] = angle_axis.angle() * angle_axis.axis()[k];
    }
    std::vector<Observation> readings;
    for (const Eigen::Vector3d& q : Mesh({500, 500, 400})) {
      Observation o;
      o.command = q;
      o.measured = Forward(layout, truth.data(), q, posed);
      readings.push_back(o);
    }
    const VerificationResult r = VerifyMachine(layout, readings, Estimated());
    EXPECT_GT(r.initial.mean_um(), 5.0) << code;
    EXPECT_LT(r.final.max_um(), 1e-3) << code;
    EXPECT_NEAR(r.identified.pose.translation.x(), tracker.translation.x(), 1.0) << code;
  }
}

// Independent reference: Gauss-Newton with central differences on [Aguado 2016] eq. 1, same weights, same free
// coefficients (power basis, evaluated here by hand), the pose as translation + rotation vector.
struct ReferenceFit {
  std::vector<double> values;
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
};

Errors LayoutErrors(const ParameterLayout& layout, const std::vector<int>& free_coefficients, const Eigen::VectorXd& v,
                    const Eigen::Vector3d& q) {
  std::array<double, 21> term{};
  for (size_t i = 0; i < free_coefficients.size(); ++i) {
    const ParameterLayout::Coefficient& c = layout.coefficients()[static_cast<size_t>(free_coefficients[i])];
    const int axis = c.term < 18 ? c.term / 6 : 0;
    const double u = c.term < 18 ? q[axis] / (0.5 * kWorkspace[axis]) : 0.0;
    term[static_cast<size_t>(c.term)] += v[static_cast<Eigen::Index>(i)] * (c.term < 18 ? std::pow(u, c.power) : 1.0);
  }
  Errors e;
  e.x_t = {term[0], term[1], term[2]};
  e.x_r = {term[3], term[4], term[5]};
  e.y_t = {term[6], term[7], term[8]};
  e.y_r = {term[9], term[10], term[11]};
  e.z_t = {term[12], term[13], term[14]};
  e.z_r = {term[15], term[16], term[17]};
  e.xwy = term[18];
  e.xwz = term[19];
  e.ywz = term[20];
  return e;
}

ReferenceFit FitIndependently(const ParameterLayout& layout, const std::vector<Observation>& readings, const Tracker& start) {
  std::vector<int> free_coefficients;
  for (size_t i = 0; i < layout.coefficients().size(); ++i) {
    if (layout.coefficients()[i].state == ParameterLayout::State::kFree) free_coefficients.push_back(static_cast<int>(i));
  }
  const Eigen::Index n = static_cast<Eigen::Index>(free_coefficients.size()), p = n + 6;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(p);
  const Eigen::AngleAxisd start_rotation(start.rotation);
  x.segment<3>(n) = start.translation + Eigen::Vector3d(2.0, -3.0, 1.0);  // start away from the truth
  x.segment<3>(n + 3) = start_rotation.angle() * start_rotation.axis() + Eigen::Vector3d(1e-3, -2e-3, 1e-3);
  // Coefficients in units of 10 um (power basis, |u| <= 2) so the numeric step suits them all.
  const double unit = 0.01;
  const auto residuals = [&](const Eigen::VectorXd& v) {
    const Eigen::Vector3d rv = v.segment<3>(n + 3);
    const Eigen::Matrix3d r = rv.norm() > 0 ? Eigen::AngleAxisd(rv.norm(), rv.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
    Eigen::VectorXd out(3 * static_cast<Eigen::Index>(readings.size()));
    for (size_t i = 0; i < readings.size(); ++i) {
      const Observation& o = readings[i];
      const Eigen::Vector3d model = SeedReading(LayoutErrors(layout, free_coefficients, unit * v.head(n), o.command), o.command, r,
                                                v.segment<3>(n));
      const Eigen::Matrix3d l = o.covariance.llt().matrixL();
      out.segment<3>(3 * static_cast<Eigen::Index>(i)) = l.triangularView<Eigen::Lower>().solve(model - o.measured);
    }
    return out;
  };
  for (int iteration = 0; iteration < 8; ++iteration) {
    const Eigen::VectorXd r0 = residuals(x);
    Eigen::MatrixXd j(r0.size(), p);
    for (Eigen::Index k = 0; k < p; ++k) {
      const double h = k < n ? 1e-4 : (k < n + 3 ? 1e-4 : 1e-7);
      Eigen::VectorXd up = x, down = x;
      up[k] += h;
      down[k] -= h;
      j.col(k) = (residuals(up) - residuals(down)) / (2 * h);
    }
    x -= j.colPivHouseholderQr().solve(r0);
  }
  ReferenceFit fit;
  for (Eigen::Index i = 0; i < n; ++i) fit.values.push_back(unit * x[i]);
  const Eigen::Vector3d rv = x.segment<3>(n + 3);
  fit.rotation = Eigen::AngleAxisd(rv.norm(), rv.normalized()).toRotationMatrix();
  fit.translation = x.segment<3>(n);
  return fit;
}

TEST(MachineVerification, MatchesAnIndependentWeightedFitOnNonPolynomialErrorsWithTrackerNoise) {
  const Truth truth = MakeTruth(11, false, 3.0);
  const Tracker tracker;
  const TrackerNoise noise = TrackerNoise::Preset("published");
  const std::vector<Observation> readings = Readings(truth, Mesh({250, 250, 200}), tracker, &noise, 5);
  const std::vector<Observation> unseen = Readings(truth, Mesh({200, 150, 150}), tracker, nullptr, 0);
  const VerificationResult r = VerifyMachine(MachineLayout(Basis::kPower, 2), readings, Estimated());
  ASSERT_TRUE(r.identified.converged) << r.identified.solver_report;
  const ParameterLayout& layout = r.identified.calibration.layout;
  const double ours = Summarize(VolumetricResiduals(layout, &r.identified.calibration.values, r.identified.pose, unseen)).mean_um();

  const ReferenceFit reference = FitIndependently(layout, readings, tracker);
  std::vector<int> free_coefficients;
  for (size_t i = 0; i < layout.coefficients().size(); ++i) {
    if (layout.coefficients()[i].state == ParameterLayout::State::kFree) free_coefficients.push_back(static_cast<int>(i));
  }
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(reference.values.data(), static_cast<Eigen::Index>(reference.values.size()));
  double theirs = 0.0;
  for (const Observation& o : unseen) {
    theirs += (SeedReading(LayoutErrors(layout, free_coefficients, v, o.command), o.command, reference.rotation, reference.translation) -
               o.measured).norm() * 1e3 / static_cast<double>(unseen.size());
  }
  const double before = Summarize(VolumetricResiduals(layout, nullptr, r.initial_pose, unseen)).mean_um();
  // The target: within 10 % of the independent fit; and the model must have learnt something, though
  // 24 urad of angle noise at 2-3 m (50-70 um across the beam) leaves its coefficients noisy.
  EXPECT_NEAR(ours, theirs, 0.1 * theirs) << "before " << before;
  EXPECT_LT(ours, 0.6 * before) << "after " << ours;
  // Weighted residuals as large as the tracker's covariances say (the sines the model cannot take add a little).
  EXPECT_GT(r.identified.weighted_rms, 0.8);
  EXPECT_LT(r.identified.weighted_rms, 2.0);
}

}  // namespace
}  // namespace fvm::stage
