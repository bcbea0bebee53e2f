// One binning rule for every histogram: [edge, edge + width), values outside in the end bins.

#include "core/histogram.h"

#include <gtest/gtest.h>

namespace fvm {
namespace {

TEST(BinCounts, LowerEdgesBelongToTheirBinAndOutliersToTheEnds) {
  EXPECT_EQ(BinCounts({0.0, 0.49, 0.5, 1.2, 1.5, -3.0, 99.0}, 0.0, 0.5, 3), (std::vector<int>{3, 1, 3}));
  EXPECT_EQ(BinCounts({-1.0, 1.0}, -2.0, 2.0, 2), (std::vector<int>{1, 1}));
  EXPECT_TRUE(BinCounts({1.0}, 0.0, 1.0, 0).empty());
}

}  // namespace
}  // namespace fvm
