// fvm against Gwyddion (Necas and Klapetek 2012), the reader users trust for other instruments' exports, on every
// real file of ../shared/realdata/surfaces/vendors that Gwyddion 2.62 reads: the grid and the count of valid points
// exactly, the pixel sizes to 4 ulp (Gwyddion keeps the field's length and divides it by the points again), and
// every valid height within 1e-9 of the map's largest height (both compute count x step + offset in doubles, in
// different orders; they differ by about 1e-16). Where the file has an intensity image, Gwyddion's second channel,
// it equals fvm's. tests/gwyddion/gwyddion_dump.c prints what Gwyddion reads; the test skips where it was not
// built (no Gwyddion development files) or ../shared is absent.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "imaging/height_map.h"
#include "core/file_io.h"
#include "imaging/io/surface_file.h"
#include "tests/support/instrument_files.h"
#include "tests/support/lext_files.h"
#include "tests/support/surface_samples.h"
#include "tests/support/test_support.h"

namespace fvm::imaging {
namespace {

const std::filesystem::path kVendors = std::filesystem::path(FVM_REALDATA_DIR) / "surfaces" / "vendors";
const std::string kGwyddionDump = FVM_GWYDDION_DUMP;

struct GwyddionChannel {
  std::string title;
  int xres = 0, yres = 0;
  double dx_m = 0, dy_m = 0;
  std::string unit_xy, unit_z;
  std::size_t masked = 0;
  std::vector<double> values;  // NaN where masked
};

// What Gwyddion reads from `file`: its channels in order, empty when it cannot read the file.
std::vector<GwyddionChannel> ReadWithGwyddion(const std::filesystem::path& file, const std::filesystem::path& home) {
  // HOME: Gwyddion looks for user plugins there; a scratch directory keeps the user's own out of the test.
  const std::string command =
      "HOME='" + home.string() + "' '" + kGwyddionDump + "' '" + file.string() + "' 2>/dev/null";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  std::string text;
  char buffer[1 << 16];
  for (std::size_t n; pipe && (n = std::fread(buffer, 1, sizeof buffer, pipe.get())) > 0;) text.append(buffer, n);
  std::istringstream in(text);
  std::vector<GwyddionChannel> channels;
  std::string word;
  while (in >> word) {
    if (word != "channel") return channels;  // "error: ..."
    GwyddionChannel c;
    int id = 0;
    in >> id;
    std::getline(in, c.title);
    in >> word >> c.xres >> c.yres >> word >> c.dx_m >> c.dy_m >> word >> word >> word >> word >> c.unit_xy >>
        c.unit_z >> word >> c.masked >> word;
    c.values.resize(static_cast<std::size_t>(c.xres) * static_cast<std::size_t>(c.yres));
    for (double& v : c.values) {
      in >> word;
      v = word == "nan" ? NAN : std::stod(word);
    }
    channels.push_back(std::move(c));
  }
  return channels;
}

class GwyddionComparison : public ::testing::TestWithParam<const char*> {};

TEST_P(GwyddionComparison, FvmReadsWhatGwyddionReads) {
  if (kGwyddionDump.empty()) GTEST_SKIP() << "gwyddion_dump was not built (no libgwyddion20-dev)";
  const std::filesystem::path file = kVendors / GetParam();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file.string() << " is absent (no ../shared)";
  const fvm::testing::TempDir home;
  const std::vector<GwyddionChannel> gwyddion = ReadWithGwyddion(file, home.path());
  ASSERT_FALSE(gwyddion.empty()) << "Gwyddion read nothing from " << file;
  const GwyddionChannel& heights = gwyddion.front();
  ASSERT_EQ(heights.unit_xy, "m");
  ASSERT_EQ(heights.unit_z, "m");

  const Surface surface = ReadSurface(file);
  ASSERT_TRUE(surface.height_map.has_value());
  const HeightMap& map = *surface.height_map;
  ASSERT_EQ(map.size_x, heights.xres);
  ASSERT_EQ(map.size_y, heights.yres);
  const double ulp4 = 4 * std::numeric_limits<double>::epsilon();
  EXPECT_NEAR(map.dx_mm, heights.dx_m * 1000.0, ulp4 * map.dx_mm);
  EXPECT_NEAR(map.dy_mm, heights.dy_m * 1000.0, ulp4 * map.dy_mm);
  EXPECT_EQ(ComputeStats(map).valid_points, map.z_mm.size() - heights.masked);

  double largest = 0, worst = 0;
  for (const double z : heights.values) largest = std::isnan(z) ? largest : std::max(largest, std::fabs(z) * 1000.0);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    const double theirs = heights.values[i] * 1000.0;
    ASSERT_EQ(std::isnan(map.z_mm[i]), std::isnan(theirs)) << "point " << i << " valid in one reader only";
    if (!std::isnan(theirs)) worst = std::max(worst, std::fabs(map.z_mm[i] - theirs));
  }
  EXPECT_LE(worst, 1e-9 * largest) << "largest difference " << worst << " mm over heights up to " << largest << " mm";
  std::cout << GetParam() << ": " << map.size_x << " x " << map.size_y << ", " << ComputeStats(map).valid_points
            << " valid, largest height difference " << worst / largest << " of the largest height\n";

  if (gwyddion.size() > 1 && gwyddion[1].xres == map.size_x && gwyddion[1].yres == map.size_y) {
    ASSERT_EQ(map.intensity.size(), map.z_mm.size()) << "Gwyddion reads an intensity image, fvm none";
    for (std::size_t i = 0; i < map.intensity.size(); ++i) {
      ASSERT_EQ(static_cast<double>(map.intensity[i]), gwyddion[1].values[i]) << "intensity at point " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(VendorFiles, GwyddionComparison,
                         ::testing::Values("test_1.plu", "test_1.dat", "test_1.opd", "test_uncompressed.sur"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string name = info.param;
                           for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

// What Gwyddion 2.62 does not read, fvm does (the other checks are in instrument_files_test.cc).
TEST(GwyddionComparison, GwyddionReadsNeitherTheNmsNorTheTmd) {
  if (kGwyddionDump.empty()) GTEST_SKIP() << "gwyddion_dump was not built (no libgwyddion20-dev)";
  if (!std::filesystem::exists(kVendors)) GTEST_SKIP() << kVendors.string() << " is absent (no ../shared)";
  const fvm::testing::TempDir home;
  for (const char* name : {"test_1.nms", "testing.tmd"}) {
    EXPECT_TRUE(ReadWithGwyddion(kVendors / name, home.path()).empty()) << name;
    EXPECT_TRUE(ReadSurface(kVendors / name).height_map.has_value()) << name;
  }
}

// The formats with no instrument file here, on files written as their descriptions say (described_formats_test.cc):
// Gwyddion reads the same grid and heights. VK4: Gwyddion spreads the field over width - 1 pixels (keyence.c, "from
// comparison with original software"), so its pixel is (width - 1) / width of the file's x_length_per_pixel, which
// fvm keeps; its light channel (the second) is the counts over 2^16.
TEST(GwyddionComparison, SyntheticVk4) {
  if (kGwyddionDump.empty()) GTEST_SKIP() << "gwyddion_dump was not built (no libgwyddion20-dev)";
  const fvm::testing::TempDir home;
  const HeightMap written = testing::SampleMap(7, 5);
  WriteFileAtomically(home.path() / "a.vk4", testing::BuildVk4(written));
  const std::vector<GwyddionChannel> gwyddion = ReadWithGwyddion(home.path() / "a.vk4", home.path());
  ASSERT_EQ(gwyddion.size(), 2u) << "Gwyddion reads the height and the light image";
  const GwyddionChannel& heights = gwyddion[0];
  const GwyddionChannel& light = gwyddion[1];
  ASSERT_EQ(light.title, " Light 0");
  ASSERT_EQ(heights.unit_z, "m");
  const HeightMap map = *ReadSurface(home.path() / "a.vk4").height_map;
  ASSERT_EQ(map.size_x, heights.xres);
  ASSERT_EQ(map.size_y, heights.yres);
  const double ulp4 = 4 * std::numeric_limits<double>::epsilon();
  EXPECT_NEAR(map.dx_mm * (map.size_x - 1) / map.size_x, heights.dx_m * 1000.0, ulp4 * map.dx_mm);
  EXPECT_NEAR(map.dy_mm * (map.size_y - 1) / map.size_y, heights.dy_m * 1000.0, ulp4 * map.dy_mm);
  EXPECT_EQ(heights.masked, 0u);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    EXPECT_NEAR(map.z_mm[i], heights.values[i] * 1000.0, 1e-12 * std::fabs(map.z_mm[i])) << "point " << i;
    EXPECT_EQ(map.intensity[i] / 65536.0, light.values[i]) << "light at point " << i;
  }
}

// LEXT: Gwyddion's lextfile.c reads the colour page as three channels, then Intensity and Height; the same pixel
// (HeightDataPerPixelX, Y) and heights. It leaves the INVALID page unread: where fvm marks a point invalid,
// Gwyddion shows the count written there (0).
TEST(GwyddionComparison, SyntheticLext) {
  if (kGwyddionDump.empty()) GTEST_SKIP() << "gwyddion_dump was not built (no libgwyddion20-dev)";
  const fvm::testing::TempDir home;
  WriteFileAtomically(home.path() / "a.lext", testing::BuildLext(testing::SampleMap(11, 5)));
  const std::vector<GwyddionChannel> gwyddion = ReadWithGwyddion(home.path() / "a.lext", home.path());
  ASSERT_EQ(gwyddion.size(), 5u) << "Gwyddion reads red, green, blue, intensity and height";
  const GwyddionChannel& heights = gwyddion[4];
  ASSERT_EQ(heights.title, " Height");
  ASSERT_EQ(heights.unit_z, "m");
  const HeightMap map = *ReadSurface(home.path() / "a.lext").height_map;
  ASSERT_EQ(map.size_x, heights.xres);
  ASSERT_EQ(map.size_y, heights.yres);
  const double ulp4 = 4 * std::numeric_limits<double>::epsilon();
  EXPECT_NEAR(map.dx_mm, heights.dx_m * 1000.0, ulp4 * map.dx_mm);
  EXPECT_NEAR(map.dy_mm, heights.dy_m * 1000.0, ulp4 * map.dy_mm);
  std::size_t compared = 0;
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isnan(map.z_mm[i])) {
      EXPECT_EQ(heights.values[i], 0.0) << "point " << i;
      continue;
    }
    EXPECT_NEAR(map.z_mm[i], heights.values[i] * 1000.0, 1e-12 * std::fabs(map.z_mm[i])) << "point " << i;
    ++compared;
  }
  EXPECT_EQ(compared, ComputeStats(map).valid_points);
}

// SUR's inversion code as Gwyddion 2.62 applies it: 1 inverts the heights, 2 also mirrors the columns, 3 the rows.
// Gwyddion inverts about the map's mean and fvm negates the counts, so the two differ by one constant height: every
// valid point's difference equals the first's. (Gwyddion leaves the non-measured points of these files unmasked:
// they are compared where fvm has a height.)
TEST(GwyddionComparison, SyntheticSurInversions) {
  if (kGwyddionDump.empty()) GTEST_SKIP() << "gwyddion_dump was not built (no libgwyddion20-dev)";
  const fvm::testing::TempDir home;
  for (std::int16_t code = 1; code <= 3; ++code) {
    std::string bytes = testing::BuildSur(testing::SampleMap(7, 5));
    testing::PutLe<std::int16_t>(bytes, 290, code);
    const std::filesystem::path file = home.path() / ("inverted" + std::to_string(code) + ".sur");
    WriteFileAtomically(file, bytes);
    const std::vector<GwyddionChannel> gwyddion = ReadWithGwyddion(file, home.path());
    ASSERT_EQ(gwyddion.size(), 1u) << "code " << code;
    const HeightMap map = *ReadSurface(file).height_map;
    ASSERT_EQ(map.size_x, gwyddion[0].xres);
    ASSERT_EQ(map.size_y, gwyddion[0].yres);
    std::optional<double> shift;
    for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
      if (std::isnan(map.z_mm[i])) continue;
      const double difference = map.z_mm[i] - gwyddion[0].values[i] * 1000.0;
      if (!shift) shift = difference;
      EXPECT_NEAR(difference, *shift, 1e-12) << "code " << code << ", point " << i;
    }
  }
}

}  // namespace
}  // namespace fvm::imaging
