#include "stage/polynomial_basis.h"

#include <gtest/gtest.h>

namespace fvm::stage {
namespace {

TEST(PolynomialBasis, KnownValuesAtHalf) {
  double out[4];
  EvaluateBasis(Basis::kPower, 3, 0.5, out);
  EXPECT_DOUBLE_EQ(out[3], 0.125);
  EvaluateBasis(Basis::kLegendre, 3, 0.5, out);
  EXPECT_DOUBLE_EQ(out[2], -0.125);     // (3u^2 - 1) / 2
  EXPECT_DOUBLE_EQ(out[3], -0.4375);    // (5u^3 - 3u) / 2
  EvaluateBasis(Basis::kChebyshev, 3, 0.5, out);
  EXPECT_DOUBLE_EQ(out[2], -0.5);       // 2u^2 - 1
  EXPECT_DOUBLE_EQ(out[3], -1.0);       // 4u^3 - 3u
}

TEST(PolynomialBasis, NormalisationMapsTravelEnds) {
  const Travel travel{-200.0, 0.0};
  EXPECT_DOUBLE_EQ(NormalisedCoordinate(Basis::kLegendre, travel, -200.0), -1.0);
  EXPECT_DOUBLE_EQ(NormalisedCoordinate(Basis::kChebyshev, travel, 0.0), 1.0);
  // Power basis: scaled, not shifted, so u = 0 at q = 0 and linear terms stay proportional to q.
  EXPECT_DOUBLE_EQ(NormalisedCoordinate(Basis::kPower, travel, -200.0), -2.0);
  EXPECT_THROW((Travel{1.0, 1.0}.Check()), std::invalid_argument);
}

TEST(PolynomialBasis, NamesRoundTrip) {
  for (Basis b : {Basis::kPower, Basis::kLegendre, Basis::kChebyshev}) EXPECT_EQ(ParseBasis(BasisName(b)), b);
  EXPECT_FALSE(ParseBasis("fourier"));
}

}  // namespace
}  // namespace fvm::stage
