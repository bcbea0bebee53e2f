#include "imaging/io/height_map_image.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "imaging/io/image_codec.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::AllOf;
using testing::ExpectSameGrid;
using testing::ExpectSameHeights;
using ::testing::HasSubstr;
using testing::SampleMap;

// A 3 x 2 image as another program writes it: given type and channels, optional resolution, no fvm metadata.
// Written through the image plugin's codec directly, below fvm's height-map writer.
template <typename T>
void WriteForeignImage(const std::filesystem::path& path, PixelType type, int channels, const std::vector<T>& pixels,
                       const std::string& resolution_unit = "", float resolution = 0) {
  ImageWriteSpec spec;
  spec.width = 3;
  spec.height = 2;
  spec.channels = channels;
  spec.type = type;
  if (channels == 2) spec.alpha_channel = 1;
  spec.resolution_unit = resolution_unit;
  spec.x_resolution = spec.y_resolution = resolution;
  std::string error;
  ASSERT_EQ(LoadImageCodec("writing a test image").write(path, spec, type, pixels.data(), &error),
            ImageWriteResult::kWritten)
      << error;
}

TEST(HeightMapImage, FloatTiffAndExrRoundTripsAreExact) {
  const HeightMap map = SampleMap();
  TempDir dir;
  for (const std::string name : {"map.tif", "map.exr"}) {
    WriteHeightMapImage(dir / name, map);
    const HeightMap back = ReadHeightMapImage(dir / name);
    ExpectSameHeights(map, back);
    ExpectSameGrid(map, back);
  }
  EXPECT_EQ(dir.Entries(), (std::vector<std::string>{"map.exr", "map.tif"}));
  EXPECT_THAT(InputErrorOf([&] { WriteHeightMapImage(dir / "map.png", map); }), HasSubstr(".tif"));
}

TEST(HeightMapImage, OptionsOverrideTheFile) {
  TempDir dir;
  WriteHeightMapImage(dir / "map.tif", SampleMap());
  HeightMapImageOptions options;
  options.dx_mm = 0.01;
  options.z_scale_mm = 2.0;
  options.z_offset_mm = 1.0;
  const HeightMap map = ReadHeightMapImage(dir / "map.tif", options);
  EXPECT_EQ(map.dx_mm, 0.01);
  EXPECT_EQ(map.dy_mm, 0.01);
  EXPECT_FLOAT_EQ(map.z_mm[0], static_cast<float>(1.0 + 2.0 * SampleMap().z_mm[0]));
}

TEST(HeightMapImage, SixteenBitCountsNeedScaleAndPixelSize) {
  TempDir dir;
  const auto file = dir / "depth16.tif";
  WriteForeignImage<std::uint16_t>(file, PixelType::kUint16, 1, {0, 1, 2, 1000, 65535, 7});
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(file); }),
              AllOf(HasSubstr("depth16.tif"), HasSubstr("--pixel-mm")));
  HeightMapImageOptions options;
  options.dx_mm = 0.002;
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(file, options); }), HasSubstr("--z-scale"));
  options.z_scale_mm = 0.0001;
  options.z_offset_mm = -1.0;
  options.invalid_value = 0.0;
  const HeightMap map = ReadHeightMapImage(file, options);
  EXPECT_TRUE(std::isnan(map.z_mm[0]));
  EXPECT_FLOAT_EQ(map.z_mm[1], static_cast<float>(-1.0 + 0.0001));
  EXPECT_FLOAT_EQ(map.z_mm[4], static_cast<float>(-1.0 + 6.5535));  // raw counts, not OpenImageIO's 0..1
  EXPECT_EQ(ComputeStats(map).valid_points, 5u);
}

TEST(HeightMapImage, ResolutionCountsInCentimetresOnly) {
  TempDir dir;
  HeightMapImageOptions scale;
  scale.z_scale_mm = 1.0;
  WriteForeignImage<std::uint16_t>(dir / "cm.tif", PixelType::kUint16, 1, {1, 2, 3, 4, 5, 6}, "cm", 5000.0f);
  EXPECT_DOUBLE_EQ(ReadHeightMapImage(dir / "cm.tif", scale).dx_mm, 0.002);
  WriteForeignImage<std::uint16_t>(dir / "dpi.tif", PixelType::kUint16, 1, {1, 2, 3, 4, 5, 6}, "in", 72.0f);
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "dpi.tif", scale); }), HasSubstr("pixel size"));
}

TEST(HeightMapImage, AlphaZeroIsInvalidAndColourIsRejected) {
  TempDir dir;
  HeightMapImageOptions options;
  options.dx_mm = 0.001;
  WriteForeignImage<float>(dir / "alpha.tif", PixelType::kFloat, 2, {1, 1, 2, 0, 3, 1, 4, 1, 5, 1, 6, 0});
  const HeightMap map = ReadHeightMapImage(dir / "alpha.tif", options);
  EXPECT_EQ(map.z_mm[0], 1.0f);
  EXPECT_TRUE(std::isnan(map.z_mm[1]));
  EXPECT_TRUE(std::isnan(map.z_mm[5]));
  WriteForeignImage<std::uint8_t>(dir / "rgb.png", PixelType::kUint8, 3, std::vector<std::uint8_t>(18, 9));
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "rgb.png", options); }), HasSubstr("3 channels"));
}

TEST(HeightMapImage, DamagedOrMissingFilesAreInputErrors) {
  TempDir dir;
  WriteHeightMapImage(dir / "map.tif", SampleMap(64, 64));
  const std::string bytes = fvm::testing::ReadText(dir / "map.tif");
  dir.Write("cut.tif", bytes.substr(0, bytes.size() / 3));
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "cut.tif"); }), HasSubstr("cut.tif"));
  dir.Write("text.tif", "not an image at all");
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "text.tif"); }), HasSubstr("cannot read it as an image"));
  dir.Write("empty.tif", "");
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "empty.tif"); }), HasSubstr("empty"));
  EXPECT_THAT(InputErrorOf([&] { ReadHeightMapImage(dir / "none.tif"); }), HasSubstr("no such file"));
}

}  // namespace
}  // namespace fvm::imaging
