#include "imaging/point_cloud.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "imaging/io/pcd_file.h"
#include "imaging/io/ply_file.h"
#include "imaging/io/point_cloud_io.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

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

// The bytes of a value as a little-endian machine stores it (PCD binary bodies, binary_little_endian PLY).
template <typename T>
std::string BytesOf(T value) {
  std::string bytes(sizeof value, '\0');
  std::memcpy(bytes.data(), &value, sizeof value);
  return bytes;
}

std::string PcdHeader(const std::string& count, int points, const std::string& data) {
  return "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT " + count + "\nWIDTH " + std::to_string(points) +
         "\nHEIGHT 1\nPOINTS " + std::to_string(points) + "\nDATA " + data + "\n";
}

// Issue 19: each of these crashed PCL's reader or read as zeros. Each must now name the file and the fault.
TEST(PointCloudIo, Issue19PcdInputsAreInputErrors) {
  TempDir dir;
  const std::string ascii = PcdHeader("1 1 1", 1, "ascii") + "1 2 3\n";
  const std::string blank_first_line = std::string(" ") + ascii.substr(ascii.find('\n'));
  dir.Write("blank.pcd", blank_first_line);
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "blank.pcd"); }),
              AllOf(HasSubstr("blank.pcd:2"), HasSubstr("starts with VERSION")));
  dir.Write("zero.pcd", PcdHeader("1 1 1", 1, "binary_compressed") + std::string(12, '\0'));
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "zero.pcd"); }),
              AllOf(HasSubstr("zero.pcd"), HasSubstr("expands to 0 bytes, but the header's FIELDS, SIZE, COUNT and POINTS need 12")));
  std::string million = PcdHeader("1000000 1 1", 1000, "ascii");
  for (int i = 0; i < 1000; ++i) million += "1 2 3\n";
  dir.Write("million.pcd", million);
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "million.pcd"); }),
              AllOf(HasSubstr("million.pcd"), HasSubstr("'x' has COUNT 1000000")));
  dir.Write("two.pcd", PcdHeader("2 1 1", 2, "ascii") + "1 2 3\n4 5 6\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "two.pcd"); }), AllOf(HasSubstr("two.pcd"), HasSubstr("COUNT 2")));
  // The same row fault on a field that is not a coordinate: the row, and how many values it should hold.
  dir.Write("rgb.pcd",
            "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 2\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n"
            "DATA ascii\n1 2 3 4\n");
  EXPECT_THAT(InputErrorOf([&] { ReadPointCloud(dir / "rgb.pcd"); }),
              AllOf(HasSubstr("rgb.pcd:10"), HasSubstr("4 values where the header's FIELDS and COUNT declare 5")));
}

TEST(PointCloudIo, PcdBodiesMustMatchTheHeader) {
  const std::string body = BytesOf(1.0f) + BytesOf(2.0f) + BytesOf(3.0f);
  EXPECT_EQ(ParsePcd(PcdHeader("1 1 1", 1, "binary") + body, "ok.pcd").points[0], Eigen::Vector3d(1, 2, 3));
  // PCL pads its binary files with zeros; anything else after the points means header and body disagree.
  EXPECT_EQ(ParsePcd(PcdHeader("1 1 1", 1, "binary") + body + std::string(100, '\0'), "pad.pcd").points.size(), 1u);
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(PcdHeader("1 1 1", 1, "binary") + body + "x", "long.pcd"); }),
              HasSubstr("long.pcd: its binary body holds 13 bytes, but the header's FIELDS, SIZE, COUNT and POINTS "
                        "need 12 (and zeros after them)"));
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(PcdHeader("1 1 1", 2, "binary") + body, "short.pcd"); }),
              HasSubstr("short.pcd: the header declares 2 points of 12 bytes, but the binary body holds 12 bytes"));
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(PcdHeader("1 1 1", 2, "ascii") + "1 2 3\n", "few.pcd"); }),
              HasSubstr("few.pcd: holds 1 data rows where the header declares POINTS 2"));
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(PcdHeader("1 1 1", 1, "ascii") + "1 2 3\n4 5 6\n", "more.pcd"); }),
              HasSubstr("more.pcd:11: more rows"));
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(PcdHeader("1 1 1", 1, "ascii") + "1 two 3\n", "word.pcd"); }),
              HasSubstr("word.pcd:10: 'two' is not a number"));
}

// A binary_compressed body built by hand: the x block as a literal run, the y block as a back reference to it
// (LZF's overlapping copy), the z block as a literal run. PCD stores compressed points field after field.
TEST(PointCloudIo, PcdBinaryCompressedWithBackReference) {
  const std::string x = BytesOf(1.0f) + BytesOf(-2.5f), z = BytesOf(5.0f) + BytesOf(6.0f);
  const std::string lzf = std::string(1, '\x07') + x + "\xC0\x07" + std::string(1, '\x07') + z;
  const std::string file = PcdHeader("1 1 1", 2, "binary_compressed") + BytesOf(std::uint32_t(lzf.size())) +
                           BytesOf(std::uint32_t(24)) + lzf;
  const PointCloud cloud = ParsePcd(file, "c.pcd", 1000.0);
  ASSERT_EQ(cloud.points.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3d(1000, 1000, 5000));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3d(-2500, -2500, 6000));
  std::string reaching_back = file;
  reaching_back[reaching_back.size() - 10] = '\x08';  // the back reference now points before the first byte
  EXPECT_THAT(InputErrorOf([&] { ParsePcd(reaching_back, "back.pcd"); }), HasSubstr("back.pcd: its LZF-compressed"));
}

TEST(PointCloudIo, PlyAsciiAndBigEndianWithOtherElements) {
  const PointCloud ascii = ParsePly(
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty uchar red\nproperty float z\n"
      "property double x\nproperty int y\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "255 3.5 1 2\n0 -1 0.25 -7\n\n9 0 0 0\n3 0 1 2\n",
      "a.ply");
  ASSERT_EQ(ascii.points.size(), 3u);
  EXPECT_EQ(ascii.points[0], Eigen::Vector3d(1, 2, 3.5));
  EXPECT_EQ(ascii.points[1], Eigen::Vector3d(0.25, -7, -1));
  EXPECT_FALSE(ascii.IsOrganised());
  std::string big = BytesOf(std::int16_t{-3}) + BytesOf(0.5f) + BytesOf(4.0f);
  std::reverse(big.begin(), big.begin() + 2);
  std::reverse(big.begin() + 2, big.begin() + 6);
  std::reverse(big.begin() + 6, big.end());
  const PointCloud binary = ParsePly(
      "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty short x\nproperty float y\nproperty float z\n"
      "end_header\n" + big,
      "b.ply");
  EXPECT_EQ(binary.points[0], Eigen::Vector3d(-3, 0.5, 4));
}

// PCL's writer keeps an organised cloud's grid in obj_info and a range_grid element: empty lists are missing
// points, read as NaN in their place.
TEST(PointCloudIo, PlyRangeGridRestoresMissingPoints) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nobj_info num_cols 2\nobj_info num_rows 2\nelement vertex 2\n"
      "property double x\nproperty double y\nproperty double z\nelement range_grid 4\n"
      "property list uchar int vertex_indices\nend_header\n";
  const std::string vertices = BytesOf(1.0) + BytesOf(2.0) + BytesOf(3.0) + BytesOf(4.0) + BytesOf(5.0) + BytesOf(6.0);
  std::string grid(1, '\x01');  // built by appending: GCC 12 warns falsely (-Wrestrict) on "\x01" + string
  grid += BytesOf(std::int32_t{1});
  grid += std::string(2, '\0');
  grid += '\x01';
  grid += BytesOf(std::int32_t{0});
  const PointCloud cloud = ParsePly(header + vertices + grid, "g.ply");
  ASSERT_EQ(cloud.width, 2);
  ASSERT_EQ(cloud.height, 2);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3d(4, 5, 6));
  EXPECT_TRUE(std::isnan(cloud.points[1].x()) && std::isnan(cloud.points[2].z()));
  EXPECT_EQ(cloud.points[3], Eigen::Vector3d(1, 2, 3));
  EXPECT_THAT(InputErrorOf([&] { ParsePly(header + vertices + grid.substr(0, grid.size() - 2), "cut.ply"); }),
              AllOf(HasSubstr("cut.ply: element 'range_grid' row 4"), HasSubstr("ends early")));
  EXPECT_THAT(InputErrorOf([&] { ParsePly(header + vertices + grid + "\n", "tail.ply"); }),
              HasSubstr("tail.ply: 1 bytes follow the last element"));
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
  // A header that names its columns but no z: a cloud without z, not three columns taken on trust.
  EXPECT_THAT(InputErrorOf([] { ParseXyz("# from a spreadsheet\nx,y,intensity\n1,2,3\n", "noz.csv"); }),
              AllOf(HasSubstr("noz.csv:2"), HasSubstr("no column 'z'")));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("# nothing\n\n", "none.xyz"); }), HasSubstr("no points"));
  EXPECT_THAT(InputErrorOf([] { ParseXyz("", "empty.xyz"); }), HasSubstr("no points"));
}

}  // namespace
}  // namespace fvm::imaging
