#include "imaging/point_cloud.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "imaging/io/point_cloud_io.h"
#include "tests/artefacts/test_support.h"
#include "tests/imaging/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::AllOf;
using testing::ExpectSameHeights;
using ::testing::HasSubstr;
using testing::SampleMap;

void ExpectSamePoints(const PointCloud& expected, const PointCloud& actual) {
  ASSERT_EQ(actual.width, expected.width);
  ASSERT_EQ(actual.height, expected.height);
  ASSERT_EQ(actual.points.size(), expected.points.size());
  for (size_t i = 0; i < expected.points.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      if (std::isnan(expected.points[i][axis])) {
        EXPECT_TRUE(std::isnan(actual.points[i][axis])) << i;
      } else {
        EXPECT_EQ(actual.points[i][axis], expected.points[i][axis]) << i << " axis " << axis;
      }
    }
  }
}

TEST(PointCloud, HeightMapToCloudAndBack) {
  const HeightMap map = SampleMap();
  const PointCloud cloud = HeightMapToCloud(map);
  ASSERT_TRUE(cloud.IsOrganised());
  EXPECT_EQ(cloud.points.size(), map.z_mm.size());
  EXPECT_DOUBLE_EQ(cloud.points[map.size_x + 2].x(), map.x0_mm + 2 * map.dx_mm);
  EXPECT_DOUBLE_EQ(cloud.points[map.size_x + 2].y(), map.y0_mm + map.dy_mm);
  EXPECT_TRUE(std::isnan(cloud.points[1].x()));
  const HeightMap back = CloudToHeightMap(cloud, "cloud");
  ExpectSameHeights(map, back);
  EXPECT_NEAR(back.dx_mm, map.dx_mm, 1e-15);
  EXPECT_NEAR(back.dy_mm, map.dy_mm, 1e-15);
  EXPECT_NEAR(back.x0_mm, map.x0_mm, 1e-12);
  EXPECT_NEAR(back.y0_mm, map.y0_mm, 1e-12);
}

TEST(PointCloud, CloudsThatAreNotGridsGiveNoHeightMap) {
  EXPECT_THAT(InputErrorOf([] {
                CloudToHeightMap(MakeUnorganisedCloud({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), "u.pcd");
              }),
              AllOf(HasSubstr("u.pcd"), HasSubstr("unorganised")));
  PointCloud skewed = HeightMapToCloud(SampleMap());
  skewed.points[3].x() += 0.0005;  // a third of a pixel off the grid
  EXPECT_THAT(InputErrorOf([&] { CloudToHeightMap(skewed, "s.pcd"); }), HasSubstr("not on a regular grid"));
  HeightMap one_column = SampleMap(1, 4);
  EXPECT_THAT(InputErrorOf([&] { CloudToHeightMap(HeightMapToCloud(one_column), "c.pcd"); }),
              HasSubstr("spacing is unknown"));
}

TEST(PointCloud, StatsCountFinitePoints) {
  const PointCloudStats stats = ComputeStats(MakeUnorganisedCloud({{1, 2, 3}, {NAN, 0, 0}, {-1, 5, 0.5}}));
  EXPECT_EQ(stats.valid_points, 2u);
  EXPECT_EQ(stats.min, Eigen::Vector3d(-1, 2, 0.5));
  EXPECT_EQ(stats.max, Eigen::Vector3d(1, 5, 3));
}

TEST(PointCloudIo, PcdPlyXyzRoundTripsAreExact) {
  TempDir dir;
  const PointCloud organised = HeightMapToCloud(SampleMap());
  const PointCloud loose = MakeUnorganisedCloud({{0.1, -200.25, 1e-9}, {150.000001, 3, -0.5}, {1, 2, 3}});
  for (const std::string name : {"c.pcd", "c.ply", "c.xyz"}) {
    WritePointCloud(dir / ("organised." + name), organised);
    ExpectSamePoints(organised, ReadPointCloud(dir / ("organised." + name)));
    WritePointCloud(dir / ("loose." + name), loose);
    ExpectSamePoints(loose, ReadPointCloud(dir / ("loose." + name)));
  }
  EXPECT_EQ(dir.Entries().size(), 6u);  // no temporary files left
}

TEST(PointCloudIo, ReadsHandWrittenPcdWithFloatFields) {
  TempDir dir;
  const auto file = dir.Write("three.pcd",
                              "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\n"
                              "SIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\n"
                              "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3 0\n0.5 -0.25 4 0\n7 8 9 0\n");
  const PointCloud cloud = ReadPointCloud(file);
  ASSERT_EQ(cloud.points.size(), 3u);
  EXPECT_FALSE(cloud.IsOrganised());
  EXPECT_EQ(cloud.points[1], Eigen::Vector3d(0.5, -0.25, 4));
  PointCloudReadOptions metres;
  metres.mm_per_unit = 1000.0;
  EXPECT_EQ(ReadPointCloud(file, metres).points[2], Eigen::Vector3d(7000, 8000, 9000));
}

TEST(PointCloudIo, BadPcdAndPlyAreInputErrors) {
  TempDir dir;
  const std::string header = "VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  dir.Write("noz.pcd", header + "DATA ascii\n1 2\n3 4\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "noz.pcd"); }), AllOf(HasSubstr("noz.pcd"), HasSubstr("'z'")));
  dir.Write("huge.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 900000000\nHEIGHT 1\n"
            "POINTS 900000000\nDATA binary\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "huge.pcd"); }), HasSubstr("declares 900000000 points"));
  dir.Write(
      "zero.pcd",
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA ascii\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "zero.pcd"); }), HasSubstr("zero.pcd"));
  dir.Write("junk.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nend_header\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "junk.ply"); }), HasSubstr("junk.ply"));
  dir.Write("empty.pcd", "");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "empty.pcd"); }), HasSubstr("empty"));
}

TEST(PointCloudIo, XyzTextVariants) {
  const PointCloud csv = ParseXyz("# exported\nid;Z;X;Y\n1; 3.5; 1; 2\n2;6;4;5;\n", "p.csv");
  ASSERT_EQ(csv.points.size(), 2u);
  EXPECT_EQ(csv.points[0], Eigen::Vector3d(1, 2, 3.5));  // columns found by their header names
  EXPECT_EQ(csv.points[1], Eigen::Vector3d(4, 5, 6));
  const PointCloud blanks = ParseXyz("1 2 3\n\n  4\t5 6 99\r\n7,8,9\n", "p.xyz");
  EXPECT_EQ(blanks.points.size(), 3u);
  EXPECT_EQ(blanks.points[2], Eigen::Vector3d(7, 8, 9));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("1 2 3\n4 five 6\n", "bad.xyz"); }),
              AllOf(HasSubstr("bad.xyz:2"), HasSubstr("'five'")));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("1 2 3\n4 5\n", "short.xyz"); }), HasSubstr("short.xyz:2"));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("1,,3\n", "gap.csv"); }), HasSubstr("gap.csv:1"));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("# nothing\n\n", "none.xyz"); }), HasSubstr("no points"));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("", "empty.xyz"); }), HasSubstr("no points"));
}

}  // namespace
}  // namespace fvm::imaging
