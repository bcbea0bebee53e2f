#include "imaging/height_map.h"

#include <gtest/gtest.h>

#include <cmath>

namespace fvm::imaging {
namespace {

TEST(HeightMap, StatsSkipInvalidPoints) {
  HeightMap map{3, 2, 0.001, 0.001, {1.0f, NAN, -2.5f, 0.5f, INFINITY, 3.0f}};
  const HeightMapStats stats = ComputeStats(map);
  EXPECT_EQ(stats.valid_points, 4u);
  EXPECT_EQ(stats.z_min_mm, -2.5);
  EXPECT_EQ(stats.z_max_mm, 3.0);
  EXPECT_EQ(map.at(2, 1), 3.0f);
}

TEST(HeightMap, AllInvalidHasNoRange) {
  const HeightMapStats stats = ComputeStats(HeightMap{2, 1, 1, 1, {NAN, NAN}});
  EXPECT_EQ(stats.valid_points, 0u);
  EXPECT_EQ(stats.z_min_mm, 0.0);
}

}  // namespace
}  // namespace fvm::imaging
