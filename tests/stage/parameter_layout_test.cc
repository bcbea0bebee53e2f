#include "stage/parameter_layout.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <ceres/jet.h>

#include <cmath>
#include <random>

#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(ParameterLayout, NamesEveryCoefficientAfterVdi2617) {
  ParameterLayout layout(AxisChain::FvmStage(), testing::FvmTravel());
  layout.SetTerm("xTx", Basis::kPower, 1);
  layout.SetTerm("yRz", Basis::kLegendre, 0);
  layout.SetTerm("EC0Y", Basis::kPower, 0);  // ISO 230-1 alias of xWy
  layout.SetTerm("xWz", Basis::kPower, 1);
  EXPECT_THAT(layout.FreeNames(), ElementsAre("xTx0", "xTx1", "yRz0", "xWy", "xWz0", "xWz1"));
  EXPECT_THROW(layout.SetTerm("xTq", Basis::kPower, 1), std::invalid_argument);
  EXPECT_THROW(layout.SetTerm("xTx", Basis::kPower, 4), std::invalid_argument);
}

TEST(ParameterLayout, FixTieAndDropChangeWhatMoves) {
  ParameterLayout layout(AxisChain::FvmStage(), testing::FvmTravel());
  layout.SetTerm("xTx", Basis::kPower, 0);
  layout.SetTerm("yTx", Basis::kPower, 0);
  layout.SetTerm("yTy", Basis::kPower, 1);
  const Eigen::Vector3d q(-50, -80, -40);

  layout.Tie("yTx0", "xTx0", 1.0);
  ASSERT_EQ(layout.NumFree(), 3);
  // XP = x - xTx - yTx to first order and exactly here (no rotations): the tie doubles xTx0's effect.
  EXPECT_NEAR(Forward(layout, {0.01, 0.0, 0.0}, q).x(), q.x() - 0.02, 1e-13);

  layout.Fix("yTy1", 0.002);  // u = y / 100 = -0.8: yTy = -0.0016 mm
  EXPECT_THAT(layout.FreeNames(), ElementsAre("xTx0", "yTy0"));
  EXPECT_NEAR(Forward(layout, {0.0, 0.0}, q).y(), q.y() + 0.0016, 1e-13);

  EXPECT_THAT([&] { layout.Fix("xTx0", 0.0); }, ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("yTx0 is tied")));
  layout.Drop("yTy1");
  EXPECT_EQ(layout.FindCoefficient("yTy1"), -1);
  EXPECT_NEAR(Forward(layout, {0.0, 0.0}, q).y(), q.y(), 1e-13);
  EXPECT_THAT([&] { layout.Fix("nope", 1.0); }, ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("xTx0 yTx0 yTy0")));
}

TEST(ParameterLayout, AutomaticDerivativesAgreeWithFiniteDifferences) {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(5, 5, -100);
  chain.instrument = Pose::FromEulerXyzDegrees({-863.527, 194.373, 677.782}, {0.0339, 0.0343, 59.4652});
  for (RotationModel model : {RotationModel::kSmallAngle, RotationModel::kExact}) {
    chain.rotation_model = model;
    const ParameterLayout layout = testing::FullLayout(
        chain, {Travel{0, 2500}, Travel{0, 1500}, Travel{0, 1200}}, 2, "xyz", Basis::kChebyshev);
    const std::vector<double> free = testing::RandomCoefficients(layout, 2, 0.05, 5e-4);
    const Eigen::Vector3d q(1700, 300, 800);
    const Eigen::MatrixXd j = ForwardJacobian(layout, free.data(), q);
    ASSERT_EQ(j.cols(), layout.NumFree());
    for (int i = 0; i < layout.NumFree(); ++i) {
      // Central differences: truncation h^2 * f''' is negligible for h = 1e-5 (the model is nearly linear in
      // its coefficients); rounding is 1e-13 mm / 1e-5 = 1e-8 relative to derivatives of order 1..2000.
      const double h = 1e-5;
      std::vector<double> up = free, down = free;
      up[static_cast<size_t>(i)] += h;
      down[static_cast<size_t>(i)] -= h;
      const Eigen::Vector3d fd = (Forward(layout, up, q) - Forward(layout, down, q)) / (2 * h);
      EXPECT_LT((j.col(i) - fd).norm(), 1e-6 * std::max(1.0, fd.norm())) << layout.FreeNames()[static_cast<size_t>(i)];
    }
  }
}

// A 9 x 9 grid over the stage; z varies by up to z_range in a pattern unrelated to x and y (or not at all).
std::vector<Eigen::Vector3d> StageGrid(double z_range) {
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) q.emplace_back(-25.0 * i, -25.0 * j, -50 + z_range * ((7 * i + 3 * j * j) % 5) / 4.0);
  return q;
}

TEST(ParameterLayout, ReportsLinearStraightnessAsAliasOfSquareness) {
  const ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 1);
  std::vector<std::string> described;
  for (const auto& a : layout.FindAliases(StageGrid(10.0))) described.push_back(a.Describe());
  // u = q / 100 for the power basis, so xTy1 * u and -q * xWy have one shape: xWy acts as -100 * xTy1.
  EXPECT_THAT(described, ::testing::IsSupersetOf({"xWy = -100 * xTy1", "xWz = -100 * xTz1", "yWz = -100 * yTz1"}));
}

TEST(ParameterLayout, FlatScansAliasTheZCoupledRotations) {
  ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 0);
  const auto aliases = layout.FindAliases(StageGrid(0.0));  // z constant: pitch and roll act as offsets
  std::vector<std::string> dependent;
  for (const auto& a : aliases) dependent.push_back(a.dependent);
  // At order 0, X and Y offsets add up, and roll/pitch of X and Y act the same at the tool point.
  // Offsets of X and Y add up (yTx0 = xTx0, ...); with z constant the squareness terms become combinations
  // of the rotations and offsets (e.g. xWz x = xRy0 x - xRy0 z + offset).
  EXPECT_THAT(dependent, ElementsAre("yTx0", "yTy0", "yTz0", "yRx0", "yRy0", "xWy", "xWz", "yWz"));
}

TEST(ParameterLayout, RefusesTiesThatWouldLeaveAFollowerWithoutASlot) {
  ParameterLayout layout(AxisChain::FvmStage(), testing::FvmTravel());
  layout.SetTerm("xTx", Basis::kPower, 0);
  layout.SetTerm("yTx", Basis::kPower, 0);
  layout.SetTerm("yTy", Basis::kPower, 0);
  layout.Tie("yTx0", "xTx0", 1.0);
  const auto refuses = [&](auto action, const std::string& message) {
    EXPECT_THAT(action, ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr(message))) << message;
  };
  // xTx0 is followed by yTx0: tying it would leave yTx0 pointing at a slot that no longer exists (the heap
  // overflow the review found). The message names both coefficients and the fix.
  refuses([&] { layout.Tie("xTx0", "yTy0", 2.0); }, "cannot tie xTx0 to yTy0: yTx0 is tied to xTx0");
  refuses([&] { layout.Tie("yTy0", "yTx0", 1.0); }, "yTx0 is itself tied to xTx0");  // chain
  refuses([&] { layout.Tie("yTy0", "yTy0", 1.0); }, "cannot follow itself");
  refuses([&] { layout.Tie("yTy0", "xTx0", std::nan("")); }, "factor is not finite");
  refuses([&] { layout.Tie("yTy0", "xTx0", INFINITY); }, "factor is not finite");
  refuses([&] { layout.Fix("xTx0", 0.0); }, "yTx0 is tied to it");
  refuses([&] { layout.Fix("yTy0", std::nan("")); }, "non-finite");
  refuses([&] { layout.Tie("yTy0", "nope", 1.0); }, "no coefficient 'nope'");
  layout.Fix("yTy0", 0.001);
  refuses([&] { layout.Tie("xTx0", "yTy0", 1.0); }, "yTy0 is fixed");

  // Every refusal left the layout as it was, and Expand fills every coefficient from the one free slot.
  ASSERT_THAT(layout.FreeNames(), ElementsAre("xTx0"));
  const double free[1] = {0.25};
  std::vector<double> all(layout.coefficients().size(), -7.0);
  layout.Expand(free, all.data());
  EXPECT_THAT(all, ElementsAre(0.25, 0.25, 0.001));

  // Re-tying to another free coefficient after freeing the follower is fine.
  layout.Free("yTx0");
  layout.Tie("xTx0", "yTx0", -1.0);
  const double free2[1] = {0.5};
  layout.Expand(free2, all.data());
  EXPECT_THAT(all, ElementsAre(-0.5, 0.5, 0.001));
}

// TermJacobian differentiates the small-angle chain by hand: it must agree with automatic differentiation of the
// forward model itself to rounding, on every chain, with errors far larger than any machine's (0.05 rad turns the
// small-angle inverse's second-order terms on) and a tool offset that gives every rotation a lever arm.
TEST(ParameterLayout, TermJacobianIsTheDerivativeOfTheForwardModel) {
  using Jet = ceres::Jet<double, kNumErrorTerms>;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coord(-800.0, 800.0), size(-1.0, 1.0);
  for (const char* code : {"FXYZ", "XFYZ", "XYFZ", "XYZF", "YXFZ", "ZYXF", "YFXZ"}) {
    AxisChain chain = AxisChain::Parse(code);
    chain.tool_offset = Eigen::Vector3d(30, -20, 100);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d q(coord(rng), coord(rng), coord(rng));
      double e[kNumErrorTerms];
      Jet ej[kNumErrorTerms];
      for (int t = 0; t < kNumErrorTerms; ++t) {
        e[t] = (GetErrorTerm(t).kind == ErrorKind::kTranslation ? 0.5 : 0.05) * size(rng);
        ej[t] = Jet(e[t], t);
      }
      Eigen::Vector3d value;
      const Eigen::Matrix<double, 3, kNumErrorTerms> j = TermJacobian(chain, e, q, &value);
      const Eigen::Matrix<Jet, 3, 1> p = ChainForward(chain, ej, Eigen::Matrix<Jet, 3, 1>(q.cast<Jet>()));
      for (int r = 0; r < 3; ++r) {
        EXPECT_EQ(value[r], ChainForward(chain, e, q)[r]) << code;
        for (int t = 0; t < kNumErrorTerms; ++t) EXPECT_NEAR(j(r, t), p[r].v[t], 1e-12 * (1.0 + std::abs(q[r]))) << code << " term " << t;
      }
      // Axes left out of `moving_axes` get no derivative; the others the same one.
      const Eigen::Matrix<double, 3, kNumErrorTerms> y_only = TermJacobian(chain, e, q, nullptr, 0b010);
      for (int t = 0; t < kNumErrorTerms; ++t) {
        if (chain.ArgumentAxis(t) == Axis::kY) {
          EXPECT_EQ(y_only.col(t), j.col(t)) << code << " term " << t;
        } else {
          EXPECT_TRUE(y_only.col(t).isZero()) << code << " term " << t;
        }
      }
    }
  }
}

}  // namespace
}  // namespace fvm::stage
