#include "imaging/io/surface_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "imaging/io/al3d.h"
#include "imaging/io/x3p.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::AllOf;
using ::testing::HasSubstr;
using testing::SampleMap;

TEST(SurfaceFile, ContentDecidesBeforeTheExtension) {
  TempDir dir;
  const HeightMap map = SampleMap();
  dir.Write("x3p-named.dat", BuildX3p(map));
  dir.Write("al3d-named.x3p", BuildAl3d(map));
  WriteHeightMapImage(dir / "map.tif", map);
  WritePointCloud(dir / "cloud.pcd", HeightMapToCloud(map));
  WritePointCloud(dir / "cloud.ply", HeightMapToCloud(map));
  dir.Write("points.dat", "1 2 3\n4 5 6\n7 8 9\n");
  EXPECT_EQ(DetectSurfaceFormat(dir / "x3p-named.dat"), SurfaceFormat::kX3p);
  EXPECT_EQ(DetectSurfaceFormat(dir / "al3d-named.x3p"), SurfaceFormat::kAl3d);
  EXPECT_EQ(DetectSurfaceFormat(dir / "map.tif"), SurfaceFormat::kImage);
  EXPECT_EQ(DetectSurfaceFormat(dir / "cloud.pcd"), SurfaceFormat::kPcd);
  EXPECT_EQ(DetectSurfaceFormat(dir / "cloud.ply"), SurfaceFormat::kPly);
  EXPECT_EQ(DetectSurfaceFormat(dir / "points.dat"), SurfaceFormat::kXyz);

  const Surface x3p = ReadSurface(dir / "x3p-named.dat");
  ASSERT_TRUE(x3p.height_map.has_value());
  EXPECT_FALSE(x3p.cloud.has_value());
  testing::ExpectSameHeights(map, *x3p.height_map);
  const Surface xyz = ReadSurface(dir / "points.dat");
  ASSERT_TRUE(xyz.cloud.has_value());
  EXPECT_EQ(xyz.cloud->points.size(), 3u);  // three points read fine; too few for a sphere is fit's business
  EXPECT_TRUE(IsPointCloudFormat(xyz.format));
  EXPECT_EQ(FormatName(SurfaceFormat::kAl3d), "al3d");
}

TEST(SurfaceFile, UnreadableFilesAreInputErrors) {
  TempDir dir;
  dir.Write("empty.x3p", "");
  EXPECT_THAT(InputErrorOf([&] { ReadSurface(dir / "empty.x3p"); }), AllOf(HasSubstr("empty.x3p"), HasSubstr("empty")));
  dir.Write("blob.bin", std::string("\x01\x02\x03\x00\xff", 5));
  EXPECT_THAT(InputErrorOf([&] { ReadSurface(dir / "blob.bin"); }), HasSubstr("not a format fvm reads"));
  EXPECT_THAT(InputErrorOf([&] { ReadSurface(dir / "missing.al3d"); }), HasSubstr("no such file"));
  EXPECT_THAT(InputErrorOf([&] { ReadSurface(dir.path()); }), HasSubstr("directory"));
  SurfaceReadOptions options;
  options.cloud.mm_per_unit = -1;
  dir.Write("p.xyz", "1 2 3\n");
  EXPECT_THAT(InputErrorOf([&] { ReadSurface(dir / "p.xyz", options); }), HasSubstr("mm per unit"));
}

}  // namespace
}  // namespace fvm::imaging
