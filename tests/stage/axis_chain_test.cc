#include "stage/axis_chain.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace fvm::stage {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
constexpr Axis X = Axis::kX;
constexpr Axis Y = Axis::kY;
constexpr Axis Z = Axis::kZ;

TEST(AxisChain, ParsesBothSidesFromTheFrameOutward) {
  const AxisChain yxfz = AxisChain::Parse("YXFZ");
  EXPECT_THAT(yxfz.part_axes, ElementsAre(Y, X));  // Y on the frame, X rides on Y ([Pérez thesis] 2.7)
  EXPECT_THAT(yxfz.tool_axes, ElementsAre(Z));
  const AxisChain xfyz = AxisChain::Parse("XFYZ");
  EXPECT_THAT(xfyz.part_axes, ElementsAre(X));
  EXPECT_THAT(xfyz.tool_axes, ElementsAre(Y, Z));
  EXPECT_THAT(AxisChain::Parse("FXYZ").tool_axes, ElementsAre(X, Y, Z));
  EXPECT_THAT(AxisChain::Parse("ZYXF").part_axes, ElementsAre(Z, Y, X));
  EXPECT_TRUE(AxisChain::Parse("ZYXF").tool_axes.empty());
}

TEST(AxisChain, RejectsMalformedCodesWithAReason) {
  for (const char* bad : {"YXZ", "YXFFZ", "YXFX", "YXFW", "XF"}) {
    try {
      AxisChain::Parse(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(bad));
    }
  }
}

TEST(AxisChain, SquarenessCarriersFollowTheSeeds) {
  // Published FVM model ([Pérez 2019] eqs. 3-4): X carries xWy and xWz, Y carries yWz.
  EXPECT_THAT(AxisChain::FvmStage().squareness_carrier, ElementsAre(X, X, Y));
  // Machine tool ([Aguado 2016] eqs. 5-6): in XFYZ, Y carries xWy, Z carries xWz and yWz.
  EXPECT_THAT(AxisChain::Parse("XFYZ").squareness_carrier, ElementsAre(Y, Z, Z));
}

TEST(AxisChain, WithoutErrorsEveryChainIsTheIdentity) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coord(-300.0, 300.0);
  const double zeros[kNumErrorTerms] = {};
  for (const char* code : {"FXYZ", "XFYZ", "XYFZ", "XYZF", "YXFZ", "ZYXF", "YFXZ"}) {
    for (RotationModel model : {RotationModel::kSmallAngle, RotationModel::kExact}) {
      AxisChain chain = AxisChain::Parse(code);
      chain.rotation_model = model;
      for (int i = 0; i < 20; ++i) {
        const Eigen::Vector3d q(coord(rng), coord(rng), coord(rng));
        EXPECT_EQ(ChainForward(chain, zeros, q), q) << code;
      }
    }
  }
}

}  // namespace
}  // namespace fvm::stage
