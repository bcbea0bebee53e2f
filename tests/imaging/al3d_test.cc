#include "imaging/io/al3d.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::AllOf;
using ::testing::HasSubstr;
using testing::SampleMap;

// An AL3D built field by field as the instrument lays it out, with a texture plane and an icon in front of the
// depth image, and a finite InvalidPixelValue as older exports have.
std::string HandMadeAl3d(const std::vector<std::pair<std::string, std::string>>& extra_tags, int cols, int rows,
                         const std::vector<float>& depth_m, size_t depth_offset) {
  std::string bytes("AliconaImaging\0\r\n", 17);
  const auto tag = [&](const std::string& key, const std::string& value) {
    std::string field(52, '\0');
    field.replace(0, key.size(), key);
    field.replace(20, value.size(), value);
    field.replace(50, 2, "\r\n");
    bytes += field;
  };
  tag("Version", "1");
  tag("TagCount", std::to_string(extra_tags.size()));
  for (const auto& [key, value] : extra_tags) tag(key, value);
  std::string comment(256, '\0');
  comment.replace(254, 2, "\r\n");
  bytes += comment;
  bytes.resize(depth_offset, '\x7f');  // texture / icon bytes the reader skips
  const size_t stride = (cols * 4 + 7) / 8 * 8;
  bytes.resize(depth_offset + rows * stride, '\0');
  for (int iy = 0; iy < rows; ++iy) {
    std::memcpy(bytes.data() + depth_offset + iy * stride, depth_m.data() + iy * cols, cols * 4);
  }
  return bytes;
}

TEST(Al3d, RoundTripKeepsFloatPrecision) {
  const HeightMap map = SampleMap(5, 3);  // 5 columns: 20-byte rows padded to 24
  TempDir dir;
  WriteAl3d(dir / "map.al3d", map);
  const HeightMap back = ReadAl3d(dir / "map.al3d");
  ASSERT_EQ(back.size_x, 5);
  ASSERT_EQ(back.size_y, 3);
  EXPECT_DOUBLE_EQ(back.dx_mm, map.dx_mm);
  EXPECT_DOUBLE_EQ(back.dy_mm, map.dy_mm);
  for (size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isnan(map.z_mm[i])) {
      EXPECT_TRUE(std::isnan(back.z_mm[i])) << i;
    } else {
      EXPECT_FLOAT_EQ(back.z_mm[i], map.z_mm[i]) << i;
    }
  }
  EXPECT_THAT(back.source, HasSubstr("AL3D"));
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"map.al3d"});
}

TEST(Al3d, ReadsHandMadeFileWithFiniteInvalidValue) {
  const float invalid = 3.4028235e38f;
  const std::vector<float> depth = {1e-6f, invalid, -2e-6f, 3e-6f, 4e-6f, 5e-6f};
  const std::string bytes = HandMadeAl3d({{"Cols", "3"},
                                          {"Rows", "2"},
                                          {"NumberOfPlanes", "1"},
                                          {"PixelSizeXMeter", "-1.75e-06"},  // sign only says the direction
                                          {"PixelSizeYMeter", "2e-06"},
                                          {"InvalidPixelValue", "3.40282e+038"},
                                          {"TextureImageOffset", "1000"},
                                          {"DepthImageOffset", "2048"}},
                                         3, 2, depth, 2048);
  const HeightMap map = ParseAl3d(bytes, "scan.al3d");
  EXPECT_DOUBLE_EQ(map.dx_mm, 0.00175);
  EXPECT_DOUBLE_EQ(map.dy_mm, 0.002);
  EXPECT_FLOAT_EQ(map.at(0, 0), 0.001f);
  EXPECT_TRUE(std::isnan(map.at(1, 0)));
  EXPECT_FLOAT_EQ(map.at(2, 0), -0.002f);
  EXPECT_FLOAT_EQ(map.at(2, 1), 0.005f);
}

TEST(Al3d, BadFilesAreInputErrors) {
  const std::string good = BuildAl3d(SampleMap(4, 4));
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d(good.substr(0, good.size() - 20), "cut.al3d"); }),
              AllOf(HasSubstr("cut.al3d"), HasSubstr("does not lie within")));
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d(good.substr(0, 100), "head.al3d"); }), HasSubstr("truncated"));
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d("GIF89a....", "x.al3d"); }), HasSubstr("not an Alicona AL3D"));
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d("", "e.al3d"); }), HasSubstr("empty"));

  std::string lying_count = good;
  lying_count.replace(17 + 52 + 20, 2, "99");  // TagCount "9" -> "99"
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d(lying_count, "c.al3d"); }), HasSubstr("TagCount"));

  const std::vector<float> depth(4, 0.0f);
  EXPECT_THAT(
      InputErrorOf([&] {
        ParseAl3d(
            HandMadeAl3d(
                {{"Rows", "2"}, {"PixelSizeXMeter", "1e-6"}, {"PixelSizeYMeter", "1e-6"}, {"DepthImageOffset", "1024"}},
                2, 2, depth, 1024),
            "nocols.al3d");
      }),
      HasSubstr("no Cols tag"));
  EXPECT_THAT(InputErrorOf([&] {
                ParseAl3d(HandMadeAl3d({{"Cols", "2"},
                                        {"Rows", "2"},
                                        {"PixelSizeXMeter", "1e-6"},
                                        {"PixelSizeYMeter", "1e-6"},
                                        {"DepthImageOffset", "0"}},
                                       2, 2, depth, 1024),
                          "texture.al3d");
              }),
              HasSubstr("no depth image"));
  EXPECT_THAT(InputErrorOf([&] {
                ParseAl3d(HandMadeAl3d({{"Cols", "2x"},
                                        {"Rows", "2"},
                                        {"PixelSizeXMeter", "1e-6"},
                                        {"PixelSizeYMeter", "1e-6"},
                                        {"DepthImageOffset", "1024"}},
                                       2, 2, depth, 1024),
                          "bad.al3d");
              }),
              HasSubstr("Cols is '2x'"));
  std::string no_crlf = good;
  no_crlf[17 + 52 * 3 - 1] = 'x';
  EXPECT_THAT(InputErrorOf([&] { ParseAl3d(no_crlf, "crlf.al3d"); }), HasSubstr("CR LF"));
}

}  // namespace
}  // namespace fvm::imaging
