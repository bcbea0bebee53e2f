#include "stage/inverse_model.h"

#include <gtest/gtest.h>

#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

TEST(InverseModel, InvertsTheFvmStageOverItsTravel) {
  const ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 2);
  const std::vector<double> free = testing::RandomCoefficients(layout, 4);
  for (double x = -200; x <= 0; x += 20) {
    for (double y = -200; y <= 0; y += 20) {
      const Eigen::Vector3d q(x, y, -50.0);
      const InverseResult r = Inverse(layout, free.data(), Forward(layout, free, q));
      ASSERT_TRUE(r.converged);
      EXPECT_LT((r.command - q).norm(), 1e-12);
      EXPECT_LE(r.iterations, 6);
    }
  }
}

TEST(InverseModel, InvertsAMachineToolSeenByATracker) {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.rotation_model = RotationModel::kExact;
  chain.tool_offset = Eigen::Vector3d(0, 0, -120);
  chain.instrument = Pose::FromEulerXyzDegrees({-863.527, 194.373, 677.782}, {0.0339, 0.0343, 59.4652});
  const ParameterLayout layout = testing::FullLayout(
      chain, {Travel{0, 2500}, Travel{0, 1500}, Travel{0, 1200}}, 3, "xyz", Basis::kChebyshev);
  const std::vector<double> free = testing::RandomCoefficients(layout, 9, 0.05, 5e-5);
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2500, 1500, 1200), Eigen::Vector3d(1234.5, 77.7, 600)}) {
    const InverseResult r = Inverse(layout, free.data(), Forward(layout, free, q));
    ASSERT_TRUE(r.converged);
    // Coordinates reach 3000 mm, where one rounding is 4.5e-13 mm: allow a few.
    EXPECT_LT((r.command - q).norm(), 2e-12);
  }
}

}  // namespace
}  // namespace fvm::stage
