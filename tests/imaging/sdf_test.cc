// ISO 25178-71 SDF (imaging/io/sdf.h): binary files laid out byte by byte in the test (surface_samples.h), ASCII
// text as the standard shows it, and bad input. The real ASCII file is in realdata_test.cc.

#include "imaging/io/sdf.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "imaging/io/surface_file.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::HasSubstr;

TEST(Sdf, BinaryFloat64HeightsAndGrid) {
  std::vector<double> values;
  for (int i = 0; i < 15; ++i) values.push_back(0.25 * i - 1.0);  // in units of Zscale = 1 nm
  values[7] = std::nan("");
  const HeightMap map = ParseSdf(testing::BinarySdf(5, 3, 2e-6, 3e-6, 1e-9, values), "b.sdf");
  ASSERT_EQ(map.size_x, 5);
  ASSERT_EQ(map.size_y, 3);
  EXPECT_DOUBLE_EQ(map.dx_mm, 2e-3);
  EXPECT_DOUBLE_EQ(map.dy_mm, 3e-3);
  ASSERT_EQ(map.z_mm.size(), 15u);
  for (int i = 0; i < 15; ++i) {
    if (i == 7) {
      EXPECT_TRUE(std::isnan(map.z_mm[7]));
    } else {
      EXPECT_DOUBLE_EQ(map.z_mm[i], values[i] * 1e-6) << i;  // nm to mm
    }
  }
  EXPECT_DOUBLE_EQ(map.at(4, 1), values[9] * 1e-6);  // profile after profile: x runs fastest
}

TEST(Sdf, BinaryInt16Heights) {
  const HeightMap map = ParseSdf(testing::BinarySdf(2, 2, 1e-6, 1e-6, 1e-8, {-300, 0, 7, 32767}, 5), "i.sdf");
  EXPECT_DOUBLE_EQ(map.z_mm[0], -300 * 1e-5);
  EXPECT_DOUBLE_EQ(map.z_mm[3], 32767 * 1e-5);
}

TEST(Sdf, AsciiAndTheCommonReader) {
  TempDir dir;
  const auto file = dir.Write("s.sdf",
                              "aISO-1.0\r\nManufacID = ISOTC213\r\nNumPoints = 3\r\nNumProfiles = 2\r\nXscale = 1.0E-6\r\n"
                              "Yscale = 5.0E-7\r\nZscale = 1.0E-6\r\nZresolution = 1.0E-9\r\nCompression = 0\r\n"
                              "DataType = 7\r\nCheckType = 0\r\n*\r\n1.5 2.5 -3\r\n4 5\r\n6\r\n*\r\n< Note > x < /Note >\r\n*\r\n");
  const Surface surface = ReadSurface(file);
  EXPECT_EQ(surface.format, SurfaceFormat::kSdf);
  ASSERT_TRUE(surface.height_map);
  const HeightMap& map = *surface.height_map;
  EXPECT_EQ(map.size_x, 3);
  EXPECT_EQ(map.size_y, 2);
  EXPECT_DOUBLE_EQ(map.dy_mm, 5e-4);
  EXPECT_DOUBLE_EQ(map.at(2, 0), -3e-3);
  EXPECT_DOUBLE_EQ(map.at(2, 1), 6e-3);
  EXPECT_THAT(map.source, HasSubstr("ISOTC213"));
}

TEST(Sdf, BadInputIsNamed) {
  const std::string head = "aISO-1.0\nNumPoints = 2\nNumProfiles = 2\nXscale = 1e-6\nYscale = 1e-6\nZscale = 1e-6\n*\n";
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(head + "1 2 3\n*\n", "a.sdf"); }),
              HasSubstr("a.sdf: 3 values where NumPoints x NumProfiles = 2 x 2 need 4"));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(head + "1 2 x 4\n*\n", "a.sdf"); }), HasSubstr("a.sdf: line 8: 'x' is not a number"));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf("aISO-1.0\nNumPoints = 2\n*\n1 2\n", "a.sdf"); }),
              HasSubstr("the header has no NumProfiles"));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(head.substr(0, head.size() - 2), "a.sdf"); }), HasSubstr("no closing line '*'"));
  std::string compressed = testing::BinarySdf(2, 1, 1e-6, 1e-6, 1e-6, {1, 2});
  compressed[78] = 1;
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(compressed, "c.sdf"); }), HasSubstr("compressed SDF is not read"));
  const std::string cut = testing::BinarySdf(4, 4, 1e-6, 1e-6, 1e-6, std::vector<double>(16, 1.0));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(cut.substr(0, cut.size() - 8), "c.sdf"); }), HasSubstr("cut short"));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(cut.substr(0, 50), "c.sdf"); }), HasSubstr("81-byte"));
  // A header that declares 2 billion points over no data fails before it allocates anything.
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(testing::BinarySdf(65535, 32767, 1e-6, 1e-6, 1e-6, {}), "h.sdf"); }),
              HasSubstr("cut short"));
  EXPECT_THAT(InputErrorOf([&] { ParseSdf("aISO-1.0\nNumPoints = 65535\nNumProfiles = 32767\nXscale = 1e-6\n"
                                          "Yscale = 1e-6\nZscale = 1e-6\n*\n1 2\n", "h.sdf"); }),
              HasSubstr("cut short"));
  std::string bad_type = cut;
  bad_type[79] = 9;
  EXPECT_THAT(InputErrorOf([&] { ParseSdf(bad_type, "c.sdf"); }), HasSubstr("DataType 9"));
}

}  // namespace
}  // namespace fvm::imaging
