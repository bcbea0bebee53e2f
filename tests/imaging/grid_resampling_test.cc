#include "imaging/grid_resampling.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/test_support.h"

namespace fvm::imaging {
namespace {

using ::testing::HasSubstr;

HeightMap Plane(int nx, int ny, double pixel, double x0, double y0) {
  HeightMap map;
  map.size_x = nx;
  map.size_y = ny;
  map.dx_mm = map.dy_mm = pixel;
  map.x0_mm = x0;
  map.y0_mm = y0;
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) map.z_mm.push_back(0.5 + 0.003 * (x0 + ix * pixel) - 0.002 * (y0 + iy * pixel));
  }
  return map;
}

// On its own grid a map resamples to itself: every node is a corner of a cell.
TEST(GridResampling, ItsOwnGridGivesTheSameHeights) {
  HeightMap map = Plane(12, 9, 0.01, 0.25, -0.5);
  map.z_mm[30] = NAN;  // the four cells around it are left out, its node stays invalid
  const HeightMap back = ResampleOnGrid(HeightMapToCloud(map), 0.01, "plane");
  ASSERT_EQ(back.size_x, map.size_x);
  ASSERT_EQ(back.size_y, map.size_y);
  EXPECT_NEAR(back.x0_mm, map.x0_mm, 1e-12);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isnan(map.z_mm[i])) {
      EXPECT_TRUE(std::isnan(back.z_mm[i]));
    } else {
      EXPECT_NEAR(back.z_mm[i], map.z_mm[i], 1e-12) << i;
    }
  }
}

// Points moved off their grid by a smooth field (a stage error): a plane stays the same plane at the new nodes,
// since bilinear interpolation of a plane is exact; nodes outside the moved points stay invalid.
TEST(GridResampling, MovedPointsOfAPlaneInterpolateExactly) {
  const HeightMap map = Plane(30, 20, 0.01, 1.0, 2.0);
  PointCloud cloud = HeightMapToCloud(map);
  for (Eigen::Vector3d& p : cloud.points) {
    const Eigen::Vector2d shift(0.0037 + 1e-4 * p.y(), -0.0021 + 2e-4 * p.x());
    p.head<2>() += shift;
    p.z() = 0.5 + 0.003 * p.x() - 0.002 * p.y();  // the same plane at the moved position
  }
  const HeightMap back = ResampleOnGrid(cloud, 0.01, "moved");
  int valid = 0;
  for (int iy = 0; iy < back.size_y; ++iy) {
    for (int ix = 0; ix < back.size_x; ++ix) {
      const double z = back.at(ix, iy);
      if (!std::isfinite(z)) continue;
      ++valid;
      const double x = back.x0_mm + ix * back.dx_mm, y = back.y0_mm + iy * back.dy_mm;
      EXPECT_NEAR(z, 0.5 + 0.003 * x - 0.002 * y, 1e-12);
    }
  }
  EXPECT_GT(valid, 28 * 18);
}

TEST(GridResampling, RefusesWhatHasNoCells) {
  const PointCloud unorganised = MakeUnorganisedCloud({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 0)});
  EXPECT_THAT(testing::InputErrorOf([&] { ResampleOnGrid(unorganised, 0.01, "u.xyz"); }), HasSubstr("unorganised"));
  const PointCloud cloud = HeightMapToCloud(Plane(3, 3, 0.01, 0, 0));
  EXPECT_THAT(testing::InputErrorOf([&] { ResampleOnGrid(cloud, 0.0, "p"); }), HasSubstr("positive"));
  EXPECT_THAT(testing::InputErrorOf([&] { ResampleOnGrid(cloud, 1e-9, "p"); }), HasSubstr("nodes"));
}

}  // namespace
}  // namespace fvm::imaging
