// The readers written from published descriptions alone, with no instrument file at hand (Keyence VK4, Zygo DATX,
// Olympus LEXT): files laid out the way the descriptions say the instruments write them read back to half a
// quantisation step, with their pixel sizes, invalid points and intensity; truncated files, absurd dimensions and
// wrong signatures are refused naming the file and the field. Gwyddion's reading of the same files is compared in
// gwyddion_comparison_test.cc.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/keyence_vk4.h"
#include "imaging/io/olympus_lext.h"
#include "imaging/io/reader_support.h"
#include "imaging/io/surface_file.h"
#include "imaging/io/zygo_datx.h"
#include "tests/support/datx_files.h"
#include "tests/support/instrument_files.h"
#include "tests/support/lext_files.h"
#include "tests/support/surface_samples.h"
#include "tests/support/test_support.h"

namespace fvm::imaging {
namespace {

using fvm::testing::TempDir;
using testing::SampleMap;

template <typename Parse>
std::string Refusal(Parse parse, const std::string& bytes, const std::string& name) {
  SCOPED_TRACE(name);
  return fvm::testing::InputErrorOf([&] { parse(bytes, name); });
}

double Lowest(const HeightMap& map) {
  double lowest = INFINITY;
  for (const double z : map.z_mm) lowest = std::isfinite(z) ? std::min(lowest, z) : lowest;
  return lowest;
}

TEST(KeyenceVk4, ReadsHeightCountsTimesTheDigitWithTheLightImage) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap read = ParseKeyenceVk4(testing::BuildVk4(map), "a.vk4");
  ASSERT_EQ(read.size_x, 7);
  ASSERT_EQ(read.size_y, 5);
  EXPECT_DOUBLE_EQ(read.dx_mm, testing::kVk4DxMm);
  EXPECT_DOUBLE_EQ(read.dy_mm, testing::kVk4DyMm);
  const double lowest = Lowest(map);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    // VK4 marks no invalid point: the writer's count 0 reads as the lowest height, 0.
    const double expected = std::isfinite(map.z_mm[i]) ? map.z_mm[i] - lowest : 0.0;
    EXPECT_NEAR(read.z_mm[i], expected, 0.5 * testing::kVk4StepMm + 1e-15) << "point " << i;
  }
  ASSERT_EQ(read.intensity.size(), map.z_mm.size());
  for (std::size_t i = 0; i < read.intensity.size(); ++i) EXPECT_EQ(read.intensity[i], testing::GreyOf(i));
  EXPECT_EQ(read.source, "Keyence VK4, calotte");

  const TempDir dir;
  WriteFileAtomically(dir.path() / "scan.bin", testing::BuildVk4(map));  // found by content, not by name
  EXPECT_EQ(ReadSurface(dir.path() / "scan.bin").format, SurfaceFormat::kVk4);
}

TEST(KeyenceVk4, TruncatedAbsurdAndForeignFilesAreRefusedNamingTheField) {
  const std::string good = testing::BuildVk4(SampleMap(6, 4));
  const std::size_t strings = 84 + 304 + 796 + 2 * 24 + 796 + 4 * 24;  // the title is optional
  for (std::size_t size = 0; size < strings; size += 1 + size / 7) {
    const std::string message = Refusal(ParseKeyenceVk4, good.substr(0, size), "cut.vk4");
    EXPECT_NE(message.find("cut.vk4"), std::string::npos) << "cut at " << size << ": " << message;
  }
  std::string wide = good;
  testing::PutLe<std::uint32_t>(wide, 84 + 304 + 796 + 48, 0xFFFFFFFFu);  // the height image's width
  EXPECT_NE(Refusal(ParseKeyenceVk4, wide, "a.vk4").find("height image says 4294967295 x 4"), std::string::npos);
  std::string depth = good;
  testing::PutLe<std::uint32_t>(depth, 84 + 304 + 796 + 48 + 8, 12u);
  EXPECT_NE(Refusal(ParseKeyenceVk4, depth, "a.vk4").find("bit depth 12"), std::string::npos);
  std::string pixel = good;
  testing::PutLe<std::uint32_t>(pixel, 84 + 168, 0u);
  EXPECT_NE(Refusal(ParseKeyenceVk4, pixel, "a.vk4").find("x_length_per_pixel"), std::string::npos);
  std::string offset = good;
  testing::PutLe<std::uint32_t>(offset, 12 + 24, 0x7FFFFFFFu);
  EXPECT_NE(Refusal(ParseKeyenceVk4, offset, "a.vk4").find("offset table's height entry"), std::string::npos);
  std::string assembled = good;
  assembled[8] = 1;
  EXPECT_NE(Refusal(ParseKeyenceVk4, assembled, "a.vk4").find("file type"), std::string::npos);
  EXPECT_NE(Refusal(ParseKeyenceVk4, std::string(4096, 'x'), "a.vk4").find("'VK4_'"), std::string::npos);
}

// The heights of a DATX are float32 nanometres (or fringes): they read back to float32's rounding.
void ExpectDatxReadBack(const HeightMap& written, const HeightMap& read) {
  ASSERT_EQ(read.size_x, written.size_x);
  ASSERT_EQ(read.size_y, written.size_y);
  EXPECT_DOUBLE_EQ(read.dx_mm, written.dx_mm);
  EXPECT_DOUBLE_EQ(read.dy_mm, written.dy_mm);
  for (std::size_t i = 0; i < written.z_mm.size(); ++i) {
    if (std::isnan(written.z_mm[i])) {
      EXPECT_TRUE(std::isnan(read.z_mm[i])) << "point " << i << " was invalid";
    } else {
      EXPECT_NEAR(read.z_mm[i], written.z_mm[i], 1e-7 * std::fabs(written.z_mm[i]) + 1e-15) << "point " << i;
    }
  }
}

TEST(ZygoDatx, ReadsNanometresAndFringesWithNoDataAndIntensity) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap read = ParseZygoDatx(testing::BuildDatx(map), "a.datx");
  ExpectDatxReadBack(map, read);
  ASSERT_EQ(read.intensity.size(), map.z_mm.size());
  for (std::size_t i = 0; i < read.intensity.size(); ++i) EXPECT_EQ(read.intensity[i], testing::GreyOf(i));
  EXPECT_NE(read.source.find("/Data/Surface/{"), std::string::npos) << read.source;

  testing::DatxWriteOptions fringes;
  fringes.unit = testing::DatxUnit::kFringes;
  fringes.intensity = false;
  const HeightMap in_fringes = ParseZygoDatx(testing::BuildDatx(map, fringes), "b.datx");
  ExpectDatxReadBack(map, in_fringes);
  EXPECT_TRUE(in_fringes.intensity.empty());

  testing::DatxWriteOptions nx2;
  nx2.nx2_layout = true;
  ExpectDatxReadBack(map, ParseZygoDatx(testing::BuildDatx(map, nx2), "c.datx"));

  const TempDir dir;
  WriteFileAtomically(dir.path() / "scan.h5", testing::BuildDatx(map));  // found by its HDF5 signature
  const Surface surface = ReadSurface(dir.path() / "scan.h5");
  EXPECT_EQ(surface.format, SurfaceFormat::kDatx);
  EXPECT_EQ(FormatName(surface.format), "datx");
}

TEST(ZygoDatx, DamagedAndForeignFilesAreRefusedNamingTheFileAndField) {
  const HeightMap map = SampleMap(6, 4);
  const std::string good = testing::BuildDatx(map);
  for (std::size_t size = 0; size < good.size(); size += 1 + size / 5) {
    const std::string message = Refusal(ParseZygoDatx, good.substr(0, size), "cut.datx");
    EXPECT_NE(message.find("cut.datx"), std::string::npos) << "cut at " << size << ": " << message;
  }
  EXPECT_NE(Refusal(ParseZygoDatx, std::string(4096, 'x'), "a.datx").find("HDF5's signature"), std::string::npos);
  // An HDF5 file that is not a DATX: no surface.
  std::string other = good;
  for (std::size_t at = other.find("Surface"); at != std::string::npos; at = other.find("Surface", at)) {
    other.replace(at, 7, "Surfacx");
  }
  EXPECT_NE(Refusal(ParseZygoDatx, other, "b.datx").find("/Data/Surface"), std::string::npos);
  // No lateral calibration: the pixel is 0.
  HeightMap uncalibrated = map;
  uncalibrated.dx_mm = 0.0;
  EXPECT_NE(Refusal(ParseZygoDatx, testing::BuildDatx(uncalibrated), "c.datx").find("X Converter"),
            std::string::npos);
}

// A DATX saved again after processing may hold two datasets in /Data/Surface; /MetaData names the measurement's
// (Root -Measurement-> -Surface-> -Path->), as SurfaceTopography reads it. The copy sorts first by name and is 1 um
// higher: it is read only when the file has no /MetaData, by the fallback (the first by name). The converters'
// Parameters may be a fixed array of doubles as well as a variable-length list.
TEST(ZygoDatx, TheSurfaceIsTheOneMetaDataNames) {
  const HeightMap map = SampleMap(6, 4);
  testing::DatxWriteOptions two;
  two.earlier_copy = true;
  const HeightMap named = ParseZygoDatx(testing::BuildDatx(map, two), "two.datx");
  ExpectDatxReadBack(map, named);
  EXPECT_NE(named.source.find("{3B8D1D1C-"), std::string::npos) << named.source;

  testing::DatxWriteOptions fixed;  // the converters' Parameters as a fixed array (HDF5's other way to store a list)
  fixed.fixed_parameters = true;
  ExpectDatxReadBack(map, ParseZygoDatx(testing::BuildDatx(map, fixed), "fixed.datx"));

  two.metadata = false;
  const HeightMap first = ParseZygoDatx(testing::BuildDatx(map, two), "no-metadata.datx");
  EXPECT_NE(first.source.find("{0000C0DE-"), std::string::npos) << first.source;
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isfinite(map.z_mm[i])) {
      EXPECT_NEAR(first.z_mm[i], map.z_mm[i] + 1e-3, 1e-7) << "point " << i;
    }
  }
}

// One damaged length in a small DATX once made the HDF5 child allocate and fill 2.3 GB before the file was refused:
// a variable-length string stored as its length (4 bytes) and its place in the global heap (the collection's
// address, 8 bytes; the object's index, 4), whose length says 1.5 GB. The child's memory cap (RLIMIT_AS) refuses it
// at once, naming the cap and the attribute. A map of a million points still reads under the cap.
TEST(ZygoDatx, AStringClaimingGigabytesIsRefusedByTheReadersMemoryCap) {
  const HeightMap map = SampleMap(6, 4);
  std::string damaged = testing::BuildDatx(map);
  const std::size_t heap = damaged.find("GCOL");
  ASSERT_NE(heap, std::string::npos) << "BuildDatx wrote no global heap";
  std::string reference;  // "Unit" = "NanoMeters": 10 characters in the collection at `heap`
  AppendBytes<std::uint32_t>(reference, 10);
  AppendBytes<std::uint64_t>(reference, heap);
  const std::size_t unit = damaged.find(reference);
  ASSERT_NE(unit, std::string::npos) << "no 10-character string in the global heap";
  damaged.replace(unit, 4, std::string("\x00\x00\x00\x60", 4));  // 0x60000000 characters: 1.5 GB
  const std::string message = Refusal(ParseZygoDatx, damaged, "damaged.datx");
  EXPECT_NE(message.find("damaged.datx"), std::string::npos) << message;
#if !defined(__SANITIZE_ADDRESS__)  // AddressSanitizer ends the child itself when an allocation fails
  EXPECT_NE(message.find("RLIMIT_AS"), std::string::npos) << message;
  EXPECT_NE(message.find("out of memory reading"), std::string::npos) << message;
#endif

  const HeightMap large = SampleMap(1000, 1000);
  const HeightMap read = ParseZygoDatx(testing::BuildDatx(large), "large.datx");
  EXPECT_EQ(read.size_x, 1000);
  EXPECT_EQ(read.size_y, 1000);
  EXPECT_EQ(read.intensity.size(), large.z_mm.size());
}

// HDF5 1.10.8 walks a global heap collection without checking it: a free space of size 0 kept it walking for ever, an
// object larger than its collection sent it past its buffers (both found by the fuzzer). Such collections are
// refused from the file's bytes before HDF5 reads them, naming the collection's place.
TEST(ZygoDatx, DamagedGlobalHeapCollectionsAreRefusedBeforeHdf5ReadsThem) {
  const std::string good = testing::BuildDatx(SampleMap(6, 4));
  const std::size_t heap = good.find("GCOL");
  ASSERT_NE(heap, std::string::npos);
  const std::size_t collection_size = LoadBytes<std::uint64_t>(good.data() + heap + 8);
  std::size_t free_space = 0;  // the object of index 0, after the strings
  for (std::size_t at = heap + 16; at + 16 <= heap + collection_size;) {
    const auto index = LoadBytes<std::uint16_t>(good.data() + at);
    const auto size = LoadBytes<std::uint64_t>(good.data() + at + 8);
    if (index == 0) {
      free_space = at;
      break;
    }
    at += 16 + (size + 7) / 8 * 8;
  }
  ASSERT_NE(free_space, 0u) << "BuildDatx's collection has no free space";
  const std::string where = "the global heap collection at byte " + std::to_string(heap);

  std::string looping = good;
  looping.replace(free_space + 8, 8, std::string(8, '\0'));
  const std::string loop = Refusal(ParseZygoDatx, looping, "loop.datx");
  EXPECT_NE(loop.find("loop.datx: " + where + ": its free space has size 0"), std::string::npos) << loop;

  std::string overrunning = good;
  overrunning[heap + 16 + 8 + 3] = 1;  // the first object's size grows by 16 MB
  const std::string overrun = Refusal(ParseZygoDatx, overrunning, "overrun.datx");
  EXPECT_NE(overrun.find("overrun.datx: " + where + ": object 1 says"), std::string::npos) << overrun;
}

TEST(OlympusLext, ReadsTheHeightPageWithItsInvalidMaskAndIntensity) {
  const HeightMap map = SampleMap(11, 5);  // 11 columns: the INVALID page's rows end inside a byte
  const TempDir dir;
  WriteFileAtomically(dir.path() / "a.lext", testing::BuildLext(map));
  const Surface surface = ReadSurface(dir.path() / "a.lext");
  ASSERT_EQ(surface.format, SurfaceFormat::kLext);
  const HeightMap& read = *surface.height_map;
  ASSERT_EQ(read.size_x, 11);
  ASSERT_EQ(read.size_y, 5);
  EXPECT_DOUBLE_EQ(read.dx_mm, testing::kLextDxMm);
  EXPECT_DOUBLE_EQ(read.dy_mm, testing::kLextDyMm);
  const double lowest = Lowest(map);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isnan(map.z_mm[i])) {
      EXPECT_TRUE(std::isnan(read.z_mm[i])) << "point " << i << " was invalid";
    } else {
      EXPECT_NEAR(read.z_mm[i], map.z_mm[i] - lowest, 0.5 * testing::kLextStepMm + 1e-15) << "point " << i;
    }
  }
  ASSERT_EQ(read.intensity.size(), map.z_mm.size());
  for (std::size_t i = 0; i < read.intensity.size(); ++i) EXPECT_EQ(read.intensity[i], testing::GreyOf(i));
}

TEST(OlympusLext, DamagedAndForeignFilesAreRefusedNamingTheFileAndField) {
  const TempDir dir;
  const std::string good = testing::BuildLext(SampleMap(6, 4));
  const auto refusal = [&](const std::string& bytes, const std::string& file) {
    WriteFileAtomically(dir.path() / file, bytes);
    return Refusal([&](const std::string&, const std::string&) { return ReadOlympusLext(dir.path() / file); },
                   bytes, file);
  };
  for (std::size_t size = 1; size < good.size(); size += 1 + size / 3) {
    const std::string message = refusal(good.substr(0, size), "cut.lext");
    EXPECT_NE(message.find("cut.lext"), std::string::npos) << "cut at " << size << ": " << message;
  }
  std::string no_pixel = good;
  const std::size_t at = no_pixel.find("125000</HeightDataPerPixelX>");
  ASSERT_NE(at, std::string::npos);
  no_pixel.replace(at, 6, "000000");
  EXPECT_NE(refusal(no_pixel, "a.lext").find("HeightDataPerPixelX"), std::string::npos);
  std::string no_heights = good;
  no_heights.replace(no_heights.find("HEIGHT"), 6, "HEIGHX");
  EXPECT_NE(refusal(no_heights, "b.lext").find("HEIGHT"), std::string::npos);
  std::string foreign = good;
  foreign.replace(foreign.find("<TiffTagDescData"), 16, "<SomethingElse_X");
  EXPECT_NE(refusal(foreign, "c.lext").find("TiffTagDescData"), std::string::npos);
}

}  // namespace
}  // namespace fvm::imaging
