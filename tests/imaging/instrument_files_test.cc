// The readers of other instruments' exports (Sensofar PLU, Zygo MetroPro DAT, Wyko OPD, Digital Surf SUR, NMS,
// GelSight TMD): files written the way the instruments lay them out (tests/support/instrument_files.h) read back to
// half a quantisation step with their grid, invalid points and intensity; truncated files, absurd dimensions and
// wrong signatures are refused naming the file and the field. The real files of ../shared/realdata/surfaces/vendors
// are checked against what they state themselves here (the .nms header's height range, the .tmd against its X3P
// conversion) and against Gwyddion in gwyddion_comparison_test.cc.

#include "tests/support/instrument_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/digital_surf_sur.h"
#include "imaging/io/gelsight_tmd.h"
#include "imaging/io/metropro_dat.h"
#include "imaging/io/nms_file.h"
#include "imaging/io/reader_support.h"
#include "imaging/io/sensofar_plu.h"
#include "imaging/io/sensofar_plux.h"
#include "imaging/io/surface_file.h"
#include "imaging/io/wyko_opd.h"
#include "imaging/io/x3p.h"
#include "tests/support/surface_samples.h"
#include "tests/support/test_support.h"

namespace fvm::imaging {
namespace {

using fvm::testing::TempDir;
using testing::SampleMap;

const std::filesystem::path kVendors = std::filesystem::path(FVM_REALDATA_DIR) / "surfaces" / "vendors";

#define SKIP_WITHOUT_VENDOR_FILES() \
  if (!std::filesystem::exists(kVendors)) GTEST_SKIP() << kVendors.string() << " is absent (no ../shared)"

// The sample map's heights and invalid points read back to half a step; the grid to float32.
void ExpectReadBack(const HeightMap& written, const HeightMap& read, double step_mm) {
  ASSERT_EQ(read.size_x, written.size_x);
  ASSERT_EQ(read.size_y, written.size_y);
  EXPECT_NEAR(read.dx_mm, written.dx_mm, 1e-7 * written.dx_mm);
  EXPECT_NEAR(read.dy_mm, written.dy_mm, 1e-7 * written.dy_mm);
  ASSERT_EQ(read.z_mm.size(), written.z_mm.size());
  for (std::size_t i = 0; i < written.z_mm.size(); ++i) {
    if (std::isnan(written.z_mm[i])) {
      EXPECT_TRUE(std::isnan(read.z_mm[i])) << "point " << i << " was invalid";
    } else {
      EXPECT_NEAR(read.z_mm[i], written.z_mm[i], 0.5 * step_mm + 1e-15) << "point " << i;
    }
  }
}

void ExpectGreyIntensity(const HeightMap& read) {
  ASSERT_EQ(read.intensity.size(), read.z_mm.size());
  for (std::size_t i = 0; i < read.intensity.size(); ++i) {
    EXPECT_EQ(read.intensity[i], static_cast<float>(testing::GreyOf(i))) << "point " << i;
  }
}

TEST(SensofarPlu, ReadsHeightsInvalidPointsAndTheColourImage) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap read = ParseSensofarPlu(testing::BuildPlu(map), "a.plu");
  ExpectReadBack(map, read, 2e-9);  // float32 micrometres: about 1e-9 mm at 0.01 mm
  ExpectGreyIntensity(read);
}

// A multi-layer measurement: the surface (layer 0) is read, and the colour image after the last layer, not the
// second layer's bytes, is its intensity.
TEST(SensofarPlu, ReadsTheSurfaceOfAMultiLayerMeasurement) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap read = ParseSensofarPlu(testing::BuildPlu(map, 3), "layers.plu");
  ExpectReadBack(map, read, 2e-9);  // float32 micrometres, as above; the other layers are 5 and 10 um lower
  ExpectGreyIntensity(read);
  ASSERT_EQ(read.notes.size(), 1u);
  EXPECT_NE(read.notes[0].find("3 layers"), std::string::npos) << read.notes[0];
}

TEST(SensofarPlux, ReadsTheFirstLayerNamedInItsIndex) {
  HeightMap map = SampleMap(7, 5);
  map.dx_mm = 0.00125, map.dy_mm = 0.0025;  // six decimals of micrometres in index.xml
  const HeightMap read = ParseSensofarPlux(testing::BuildPlux(map), "a.plux");
  ExpectReadBack(map, read, 2e-9);
  const TempDir dir;
  WriteFileAtomically(dir.path() / "a.plux", testing::BuildPlux(map));
  EXPECT_EQ(ReadSurface(dir.path() / "a.plux").format, SurfaceFormat::kPlux);
}

TEST(MetroProDat, ReadsPhaseAsHeightsWithItsIntensity) {
  HeightMap map = SampleMap(7, 5);
  map.dy_mm = map.dx_mm;  // MetroPro has one lateral resolution
  const HeightMap read = ParseMetroProDat(testing::BuildMetroPro(map), "a.dat");
  ExpectReadBack(map, read, testing::MetroProStepMm());
  ExpectGreyIntensity(read);
}

TEST(WykoOpd, ReadsColumnsBottomUpWithItsImage) {
  HeightMap map = SampleMap(7, 5);
  map.dy_mm = map.dx_mm * 1.25;  // an aspect other than 1
  const HeightMap read = ParseWykoOpd(testing::BuildOpd(map), "a.opd");
  ExpectReadBack(map, read, testing::OpdStepMm());
  ExpectGreyIntensity(read);
}

// The heights' block under Vision's other names, and a Mult above 32767 (a uint16, not a negative int16).
TEST(WykoOpd, ReadsTheHeightsUnderTheirOtherNamesAndALargeMult) {
  const HeightMap map = SampleMap(7, 5);
  for (const char* block : {"RAW DATA", "OPD", "Raw"}) {
    ExpectReadBack(map, ParseWykoOpd(testing::BuildOpd(map, block), "a.opd"), testing::OpdStepMm());
  }
  HeightMap flat = map;  // within int16 counts of 632.8 nm / 40000
  for (double& z : flat.z_mm) z *= 1e-2;
  const std::uint16_t mult = 40000;
  ExpectReadBack(flat, ParseWykoOpd(testing::BuildOpd(flat, "RAW_DATA", mult), "b.opd"),
                 static_cast<double>(632.8f) / mult * 1e-6);
}

using Parser = std::function<HeightMap(const std::string&, const std::string&)>;

// The message of the InputError `parse` throws on `bytes`, or a failure naming the file.
std::string Refusal(const Parser& parse, const std::string& bytes, const std::string& name) {
  SCOPED_TRACE(name);
  return fvm::testing::InputErrorOf([&] { parse(bytes, name); });
}

// The inversion code (bytes 290-291) as Gwyddion 2.62 applies it (gwyddion_comparison_test.cc checks Gwyddion): 1
// inverts the heights, 2 also mirrors the columns, 3 the rows; each with a note. Codes beyond 3 are refused.
TEST(DigitalSurfSur, AppliesTheInversionCode) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap plain = ParseDigitalSurfSur(testing::BuildSur(map), "a.sur");
  for (std::int16_t code = 1; code <= 3; ++code) {
    std::string bytes = testing::BuildSur(map);
    testing::PutLe<std::int16_t>(bytes, 290, code);
    const HeightMap read = ParseDigitalSurfSur(bytes, "inverted.sur");
    ASSERT_EQ(read.notes.size(), 1u);
    EXPECT_NE(read.notes[0].find("inversion code is " + std::to_string(code)), std::string::npos) << read.notes[0];
    for (int iy = 0; iy < map.size_y; ++iy) {
      for (int ix = 0; ix < map.size_x; ++ix) {
        const int from_x = code == 2 ? map.size_x - 1 - ix : ix, from_y = code == 3 ? map.size_y - 1 - iy : iy;
        const double expected = -plain.at(from_x, from_y);
        if (std::isnan(expected)) {
          EXPECT_TRUE(std::isnan(read.at(ix, iy))) << "code " << code << " at " << ix << ", " << iy;
        } else {
          EXPECT_EQ(read.at(ix, iy), expected) << "code " << code << " at " << ix << ", " << iy;
        }
      }
    }
  }
  std::string unknown = testing::BuildSur(map);
  testing::PutLe<std::int16_t>(unknown, 290, 4);
  EXPECT_NE(Refusal(ParseDigitalSurfSur, unknown, "a.sur").find("inversion code is 4"), std::string::npos);
}

TEST(DigitalSurfSur, ReadsPlainAndCompressedWithNonMeasuredPoints) {
  const HeightMap map = SampleMap(7, 5);
  ExpectReadBack(map, ParseDigitalSurfSur(testing::BuildSur(map), "a.sur"), testing::SurStepMm());
  ExpectReadBack(map, ParseDigitalSurfSur(testing::BuildSur(map, true), "b.sur"), testing::SurStepMm());
}

TEST(Nms, ReadsCountsOverItsHeightRange) {
  HeightMap map = SampleMap(7, 5);
  for (double& z : map.z_mm) z = std::isfinite(z) ? z : 0.0;  // NMS marks no invalid point
  const HeightMap read = ParseNms(testing::BuildNms(map, -20.0, 20.0), "a.nms");
  ExpectReadBack(map, read, 40.0 / 65535.0 / 1000.0);
  ExpectGreyIntensity(read);
}

TEST(GelSightTmd, RoundTripsFloat32Heights) {
  const HeightMap map = SampleMap(7, 5);
  const HeightMap read = ParseGelSightTmd(BuildGelSightTmd(map), "a.tmd");
  ExpectReadBack(map, read, 2e-9);
  EXPECT_FLOAT_EQ(read.x0_mm, map.x0_mm);
}

// The comment after the signature as a field of 24 bytes (SurfaceTopography's reading of TMD) rather than a NUL-ended
// string: the header after the field, found because only there does the grid fill the file.
TEST(GelSightTmd, ReadsACommentFieldOf24Bytes) {
  const HeightMap map = SampleMap(7, 5);
  std::string fixed = BuildGelSightTmd(map);  // signature (32 bytes), an empty comment (its NUL), the header
  fixed.replace(32, 1, std::string("GelSight Mobile\0\0\0\0\0\0\0\0\0", 24));
  const HeightMap read = ParseGelSightTmd(fixed, "field.tmd");
  ExpectReadBack(map, read, 2e-9);
  EXPECT_EQ(read.source, "GelSight TMD v2.0, GelSight Mobile");
  std::string full = fixed;  // 24 characters, no NUL in the field
  full.replace(32, 24, "GelSight Mobile 2 scan 7");
  EXPECT_EQ(ParseGelSightTmd(full, "full.tmd").source, "GelSight TMD v2.0, GelSight Mobile 2 scan 7");
}

// Every format recognised by its content under a neutral name, except NMS, which has no signature.
TEST(InstrumentFiles, AreRecognisedByTheirContent) {
  const TempDir dir;
  const HeightMap map = SampleMap(4, 3);
  const auto detected = [&](const std::string& bytes) {
    WriteFileAtomically(dir.path() / "export.bin", bytes);
    return DetectSurfaceFormat(dir.path() / "export.bin");
  };
  EXPECT_EQ(detected(testing::BuildPlu(map)), SurfaceFormat::kPlu);
  EXPECT_EQ(detected(testing::BuildMetroPro(map)), SurfaceFormat::kMetroPro);
  EXPECT_EQ(detected(testing::BuildOpd(map)), SurfaceFormat::kOpd);
  EXPECT_EQ(detected(testing::BuildSur(map)), SurfaceFormat::kSur);
  EXPECT_EQ(detected(testing::BuildSur(map, true)), SurfaceFormat::kSur);
  EXPECT_EQ(detected(BuildGelSightTmd(map)), SurfaceFormat::kTmd);
  WriteFileAtomically(dir.path() / "export.nms", testing::BuildNms(map, 0, 1));
  const Surface nms = ReadSurface(dir.path() / "export.nms");
  EXPECT_EQ(nms.format, SurfaceFormat::kNms);
  EXPECT_EQ(FormatName(nms.format), "nms");
}

struct Format {
  std::string name;
  Parser parse;
  std::string bytes;
};

std::vector<Format> Formats() {
  const HeightMap map = SampleMap(6, 4);
  return {{"cut.plu", ParseSensofarPlu, testing::BuildPlu(map)},
          {"cut.dat", ParseMetroProDat, testing::BuildMetroPro(map)},
          {"cut.opd", ParseWykoOpd, testing::BuildOpd(map)},
          {"cut.sur", ParseDigitalSurfSur, testing::BuildSur(map)},
          {"zip.sur", ParseDigitalSurfSur, testing::BuildSur(map, true)},
          {"cut.nms", ParseNms, testing::BuildNms(map, -20, 20)},
          {"cut.tmd", ParseGelSightTmd, BuildGelSightTmd(map)},
          {"cut.plux", [](const std::string& b, const std::string& n) { return ParseSensofarPlux(b, n); },
           testing::BuildPlux(map)}};
}

// Cut anywhere, a file is refused with its name; never read as a smaller map, never a crash. (The PLU's colour
// image and the NMS intensity are optional: cut inside them, the heights still read.)
TEST(InstrumentFiles, TruncatedFilesAreRefusedNamingTheFile) {
  for (const Format& f : Formats()) {
    const std::size_t heights_end = f.name == "cut.plu"   ? 508 + 4 * 24
                                    : f.name == "cut.nms" ? 3468 + 2 * 24
                                                          : f.bytes.size();
    for (std::size_t size = 0; size < heights_end; size += 1 + size / 7) {
      const std::string message = Refusal(f.parse, f.bytes.substr(0, size), f.name);
      EXPECT_NE(message.find(f.name), std::string::npos) << f.name << " cut at " << size << ": " << message;
    }
  }
}

TEST(InstrumentFiles, AbsurdDimensionsAreRefusedNamingTheField) {
  const HeightMap map = SampleMap(6, 4);
  std::string plu = testing::BuildPlu(map);
  testing::PutLe<std::uint32_t>(plu, 504, 0xFFFFFFFFu);
  EXPECT_NE(Refusal(ParseSensofarPlu, plu, "a.plu").find("data block says 4294967295 x 4"), std::string::npos);
  std::string dat = testing::BuildMetroPro(map);
  testing::PutBe<std::uint16_t>(dat, 68, 60000);
  EXPECT_NE(Refusal(ParseMetroProDat, dat, "a.dat").find("cn_n_bytes"), std::string::npos);
  std::string opd = testing::BuildOpd(map);
  testing::PutLe<std::uint16_t>(opd, 2 + 24 * 7, 65535);  // RAW_DATA's column count
  EXPECT_NE(Refusal(ParseWykoOpd, opd, "a.opd").find("RAW_DATA"), std::string::npos);
  std::string sur = testing::BuildSur(map);
  testing::PutLe<std::int32_t>(sur, 108, 2000000000);
  EXPECT_NE(Refusal(ParseDigitalSurfSur, sur, "a.sur").find("points per line"), std::string::npos);
  std::string nms = testing::BuildNms(map, 0, 1);
  testing::PutLe<std::uint32_t>(nms, 1368, 100000);
  EXPECT_NE(Refusal(ParseNms, nms, "a.nms").find("100000 x 4"), std::string::npos);
  std::string tmd = BuildGelSightTmd(map);
  testing::PutLe<std::uint32_t>(tmd, 33, 0);
  EXPECT_NE(Refusal(ParseGelSightTmd, tmd, "a.tmd").find("0 x 4"), std::string::npos);
  std::string pixel = testing::BuildPlu(map);
  testing::PutLe<float>(pixel, 404, 0.0f);
  EXPECT_NE(Refusal(ParseSensofarPlu, pixel, "a.plu").find("mppx"), std::string::npos);
}

TEST(InstrumentFiles, WrongSignaturesAreRefusedNamingTheFormat) {
  const std::string junk(4096, 'x');
  EXPECT_NE(Refusal(ParseMetroProDat, junk, "a.dat").find("MetroPro magic"), std::string::npos);
  EXPECT_NE(Refusal(ParseWykoOpd, junk, "a.opd").find("'Directory'"), std::string::npos);
  EXPECT_NE(Refusal(ParseDigitalSurfSur, junk, "a.sur").find("DIGITAL SURF"), std::string::npos);
  EXPECT_NE(Refusal(ParseGelSightTmd, junk, "a.tmd").find("Binary TrueMap"), std::string::npos);
  EXPECT_NE(Refusal(ParseNms, junk, "a.nms").find("header size"), std::string::npos);
  std::string profile = testing::BuildPlu(SampleMap(6, 4));
  testing::PutLe<std::uint32_t>(profile, 428, 1u);
  EXPECT_NE(Refusal(ParseSensofarPlu, profile, "a.plu").find("profile"), std::string::npos);
}

// The real NMS file against its own header: its heights span exactly the header's height range (2.689 to
// 6.007 um), at the header's grid and pixel.
TEST(RealInstrumentFiles, NmsSpansItsHeaderRange) {
  SKIP_WITHOUT_VENDOR_FILES();
  const std::string bytes = ReadFileBytes(kVendors / "test_1.nms");
  const HeightMap map = ReadNms(kVendors / "test_1.nms");
  double low = LoadBytes<double>(bytes.data() + 16), high = LoadBytes<double>(bytes.data() + 24);
  const HeightMapStats stats = ComputeStats(map);
  EXPECT_EQ(map.size_x, 512);
  EXPECT_EQ(map.size_y, 512);
  EXPECT_EQ(stats.valid_points, 512u * 512u);
  EXPECT_DOUBLE_EQ(stats.z_min_mm * 1000.0, low);
  EXPECT_DOUBLE_EQ(stats.z_max_mm * 1000.0, high);
  EXPECT_NEAR(map.dx_mm, 312.4999911618964e-6, 1e-18);
  EXPECT_EQ(map.intensity.size(), map.z_mm.size());
}

// testing.tmd against its X3P conversion by x3ptools: the same grid and the same numbers. x3ptools copied the
// TMD's millimetres into the X3P's metre fields unchanged, so the X3P reads 1000 times larger in every length;
// the test states that factor rather than hiding it.
TEST(RealInstrumentFiles, TmdEqualsItsX3pConversion) {
  SKIP_WITHOUT_VENDOR_FILES();
  const HeightMap tmd = ReadGelSightTmd(kVendors / "testing.tmd");
  const HeightMap x3p = ReadX3p(kVendors / "testing.x3p");
  ASSERT_EQ(tmd.size_x, 30);
  ASSERT_EQ(tmd.size_y, 20);
  ASSERT_EQ(x3p.size_x, tmd.size_x);
  ASSERT_EQ(x3p.size_y, tmd.size_y);
  EXPECT_NEAR(x3p.dx_mm, 1000.0 * tmd.dx_mm, 1e-12 * x3p.dx_mm);
  for (std::size_t i = 0; i < tmd.z_mm.size(); ++i) {
    ASSERT_FALSE(std::isnan(tmd.z_mm[i])) << i;
    EXPECT_NEAR(x3p.z_mm[i], 1000.0 * tmd.z_mm[i], 1e-12 * std::fabs(x3p.z_mm[i]) + 1e-300) << "point " << i;
  }
}

}  // namespace
}  // namespace fvm::imaging
