// Focus stacks on disk: the CSV list (relative paths, order, errors with file and line), the images in 8 and 16
// bit, and a stack written as files rebuilt end to end as fvm focus does it, to the same heights as in memory.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/simulation/focus_stack_render.h"
#include "imaging/io/focus_stack_files.h"
#include "imaging/io/focus_stack_io.h"
#include "imaging/focus_variation.h"
#include "tests/support/test_support.h"

namespace fvm {
namespace {

void ExpectError(const std::filesystem::path& list, const std::string& part) {
  const std::string message = testing::InputErrorOf([&] { (void)imaging::ReadFocusStackList(list); });
  EXPECT_NE(message.find(part), std::string::npos) << message;
}

using testing::ExpectInputError;

TEST(FocusStackIo, ListResolvesRelativePathsAndRefusesBadStacks) {
  testing::TempDir dir;
  const auto list = dir.Write("stack.csv", "# a stack\nfile,z_mm\nimg0.png,0.010\nsub/img1.png,0.011\n/abs.png,0.012\n");
  const auto entries = imaging::ReadFocusStackList(list);
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[0].file, dir.path() / "img0.png");
  EXPECT_EQ(entries[1].file, dir.path() / "sub/img1.png");
  EXPECT_EQ(entries[2].file, std::filesystem::path("/abs.png"));
  EXPECT_DOUBLE_EQ(entries[1].z_mm, 0.011);
  EXPECT_EQ(entries[2].line, 5);

  ExpectError(dir.Write("one.csv", "file,z_mm\na.png,0\n"), "1 image(s); a focus stack needs at least 3");
  ExpectError(dir.Write("header.csv", "name,z\na.png,0\n"), "header.csv:1: the header has no column 'file'");
  ExpectError(dir.Write("repeat.csv", "file,z_mm\na.png,0\nb.png,0.001\nc.png,0.001\n"), "repeat.csv:4: z = 0.001");
  ExpectError(dir.Write("order.csv", "file,z_mm\na.png,0\nb.png,0.001\nc.png,0.0005\n"), "order.csv:4");
  ExpectError(dir.Write("number.csv", "file,z_mm\na.png,zero\n"), "number.csv:2: column 'z_mm' (field 2): 'zero' is not a number");
  ExpectError(dir / "missing.csv", "missing.csv");
  ExpectError(dir.Write("quoted.csv", "file,z_mm\n\"a,1.png\",0\nb.png,1,5\n"),
              "quoted.csv:3: 3 fields where the header (line 1) has 2; write numbers with '.' as the decimal mark");

  // The list is bounded before any image is read: 10000 images at most (a stack has tens to hundreds).
  std::string many = "file,z_mm\n";
  for (int i = 0; i <= 10000; ++i) {  // appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "i" + ...
    many += 'i';
    many += std::to_string(i);
    many += ".png,";
    many += std::to_string(i);
    many += '\n';
  }
  ExpectError(dir.Write("many.csv", many), "many.csv:10002: more than 10000 rows");
  many.resize(many.rfind("i10000.png"));
  EXPECT_EQ(imaging::ReadFocusStackList(dir.Write("most.csv", many)).size(), 10000u);
}

TEST(FocusStackIo, ImagesRoundTripIn8And16Bit) {
  testing::TempDir dir;
  imaging::StackImage image8{3, 2, std::vector<std::uint8_t>{0, 1, 2, 3, 254, 255}};
  imaging::StackImage image16{3, 2, std::vector<std::uint16_t>{0, 1, 300, 4000, 65534, 65535}};
  imaging::WriteStackImage(dir / "a.png", image8);
  imaging::WriteStackImage(dir / "b.tif", image16);
  EXPECT_EQ(std::get<std::vector<std::uint8_t>>(imaging::ReadStackImage(dir / "a.png").pixels),
            std::get<std::vector<std::uint8_t>>(image8.pixels));
  EXPECT_EQ(std::get<std::vector<std::uint16_t>>(imaging::ReadStackImage(dir / "b.tif").pixels),
            std::get<std::vector<std::uint16_t>>(image16.pixels));
  const std::string message = testing::InputErrorOf([&] { (void)imaging::ReadStackImage(dir.Write("x.png", "no")); });
  EXPECT_NE(message.find("x.png"), std::string::npos) << message;
}

// PNG is lossless, so the stack read back from files gives exactly the heights of the stack in memory.
TEST(FocusStackIo, StackFilesEndToEnd) {
  testing::TempDir dir;
  const imaging::HeightMap truth = artefacts::TiltedPlane(96, 64, 0.001, 0.006, 0.05, 0.02);
  artefacts::FocusStackRenderOptions ro;
  ro.z_mm = artefacts::EvenZSteps(0.0, 0.001, 16);
  const artefacts::RenderedFocusStack stack = artefacts::RenderFocusStack(truth, ro);
  std::string csv = "file,z_mm\n";
  for (std::size_t k = 0; k < stack.images.size(); ++k) {
    std::string name = "z";  // appended, not `"z" + ...`: GCC 12 warns falsely (-Wrestrict) on the latter
    name += std::to_string(k);
    name += ".png";
    imaging::WriteStackImage(dir / name, stack.images[k]);
    csv += name + "," + std::to_string(stack.z_mm[k]) + "\n";
  }
  const auto entries = imaging::ReadFocusStackList(dir.Write("stack.csv", csv));
  imaging::FocusVariationOptions o;
  imaging::FocusAccumulator accumulator(o);
  for (const auto& e : entries) accumulator.Add(imaging::ReadStackImage(e.file).View(), e.z_mm, e.file.string());
  const imaging::FocusResult from_files = accumulator.Finish();
  const imaging::FocusResult in_memory = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  ASSERT_EQ(from_files.height.z_mm.size(), in_memory.height.z_mm.size());
  std::size_t valid = 0;
  double sum = 0.0;
  for (std::size_t i = 0; i < in_memory.height.z_mm.size(); ++i) {
    const float a = from_files.height.z_mm[i], b = in_memory.height.z_mm[i];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
    if (std::isfinite(a)) ++valid, sum += (double(a) - truth.z_mm[i]) * (double(a) - truth.z_mm[i]);
  }
  // The plane spans 6 .. 11.9 um in a 0 .. 15 um stack: every point has its peak inside.
  EXPECT_GT(valid, in_memory.height.z_mm.size() * 99 / 100);
  EXPECT_LT(std::sqrt(sum / double(valid)), 0.1e-3);
}

// The same stack named as a directory of images (z from the step) and read through the files' path: the heights
// of the in-memory reconstruction bit for bit, the all-in-focus image the rendered pixels at each pixel's best
// image; aligned, a stack that does not move keeps its heights to within the error; bad inputs name themselves.
TEST(FocusStackIo, DirectoryStackTextureAndAlignment) {
  testing::TempDir dir;
  // Coarser grain than elsewhere (2 px): alignment registers smoothed images, as real scenes allow.
  const imaging::HeightMap truth = artefacts::TiltedPlane(256, 192, 0.001, 0.006, 0.02, 0.01);
  artefacts::FocusStackRenderOptions ro;
  ro.texture_sigma_px = 2.0;
  ro.z_mm = artefacts::EvenZSteps(0.0, 0.001, 16);
  const artefacts::RenderedFocusStack stack = artefacts::RenderFocusStack(truth, ro);
  std::filesystem::create_directories(dir.path() / "frames");
  for (std::size_t k = 0; k < stack.images.size(); ++k) {
    std::string name = "f";
    name += std::to_string(100 + k);  // sorts by name in focus order
    name += ".png";
    imaging::WriteStackImage(dir.path() / "frames" / name, stack.images[k]);
  }
  const auto entries = imaging::ResolveFocusStack({dir.path() / "frames"}, 0.001);
  ASSERT_EQ(entries.size(), 16u);
  EXPECT_DOUBLE_EQ(entries[15].z_mm, 0.015);
  imaging::FocusStackFilesOptions o;
  o.colour = true;
  const imaging::FocusStackFilesResult files = imaging::ReconstructFocusStackFiles(entries, o);
  const imaging::FocusResult memory = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o.focus);
  ASSERT_EQ(files.focus.height.z_mm.size(), memory.height.z_mm.size());
  EXPECT_TRUE(files.eight_bit);
  EXPECT_EQ(files.focus.texture_channels, 1);
  const imaging::StackImage texture = imaging::AllInFocusImage(files.focus, true);
  const auto& sharp = std::get<std::vector<std::uint8_t>>(texture.pixels);
  std::size_t texture_checked = 0;
  for (std::size_t i = 0; i < memory.height.z_mm.size(); ++i) {
    const double a = files.focus.height.z_mm[i], b = memory.height.z_mm[i];
    ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << i;
  }
  // The texture comes from the 3 px window's best image, which the result does not hold; its pixel equals the
  // rendered pixel of one image of the stack near the surface (within 2 images of the height).
  for (std::size_t i = 0; i < sharp.size(); i += 7) {
    const int near = int(std::lround(truth.z_mm[i] / 0.001));
    bool found = false;
    for (int k = std::max(0, near - 2); k <= std::min(15, near + 2); ++k) {
      found |= std::get<std::vector<std::uint8_t>>(stack.images[std::size_t(k)].pixels)[i] == sharp[i];
    }
    texture_checked += found;
  }
  EXPECT_GT(texture_checked, sharp.size() / 7 * 95 / 100);

  o.align = true;
  const imaging::FocusStackFilesResult aligned = imaging::ReconstructFocusStackFiles(entries, o);
  ASSERT_EQ(aligned.alignment.size(), 16u);
  // The first images are far out of focus everywhere (the plane starts 6 um up): those pairs share no texture.
  std::printf("unregistered: %d of 15 pairs\n", aligned.unregistered);
  EXPECT_LT(aligned.unregistered, 10);
  for (const auto& t : aligned.alignment) {
    // A stack that does not move: identity to 0.2 % in scale and 0.6 px in shift. The registration of
    // differently focused images is pulled along the plane's tilt (x), where the sharp band moves from image to
    // image; 0.4-0.5 px measured.
    EXPECT_NEAR(t[0], 1.0, 2e-3);
    EXPECT_NEAR(t[4], 1.0, 2e-3);
    EXPECT_NEAR(t[2], 0.0, 0.6);
    EXPECT_NEAR(t[5], 0.0, 0.6);
  }
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < truth.z_mm.size(); ++i) {
    const double d = aligned.focus.height.z_mm[i] - truth.z_mm[i];
    if (std::isfinite(d)) sum += d * d, ++n;
  }
  EXPECT_GT(n, truth.z_mm.size() * 9 / 10);
  EXPECT_LT(std::sqrt(sum / double(n)), 0.1e-3);

  ExpectInputError([&] { (void)imaging::ResolveFocusStack({dir.Write("s.csv", "file,z_mm\n")}, 0.001); },
                   "--z-step-mm is for images");
  std::filesystem::create_directories(dir.path() / "empty");
  ExpectInputError([&] { (void)imaging::ResolveFocusStack({dir.path() / "empty"}, std::nullopt); }, "no image files");
  ExpectInputError([&] { (void)imaging::ResolveFocusStack({dir.path() / "a.png", dir.path() / "b.png"}, std::nullopt); },
                   "at least 3");
}

}  // namespace
}  // namespace fvm
