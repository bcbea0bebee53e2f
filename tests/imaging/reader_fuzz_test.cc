// A brief fuzz of the parsers: valid files with random bytes changed (fixed seeds) must read or fail with an
// InputError, never with another exception or a crash. Structure-aware rounds mutate main.xml and rebuild the
// container with matching checksums, so that the mutations reach the XML reader instead of stopping at the CRC.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/input_error.h"
#include "imaging/io/al3d.h"
#include "imaging/io/digital_surf_sur.h"
#include "imaging/io/gelsight_tmd.h"
#include "imaging/io/keyence_vk4.h"
#include "imaging/io/zygo_datx.h"
#include "tests/support/datx_files.h"
#include "imaging/io/metropro_dat.h"
#include "imaging/io/nms_file.h"
#include "imaging/io/sensofar_plu.h"
#include "imaging/io/sensofar_plux.h"
#include "imaging/io/wyko_opd.h"
#include "imaging/io/height_map_image.h"
#include "imaging/io/md5.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/sdf.h"
#include "imaging/io/x3p.h"
#include "imaging/io/zip_archive.h"
#include "tests/support/instrument_files.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::TempDir;
using testing::SampleMap;

constexpr int kRounds = 300;

// Changes 1 to 4 bytes, sometimes cuts the tail or inserts digits (lengths are where parsers trust numbers).
std::string Mutate(std::string bytes, std::mt19937& random) {
  std::uniform_int_distribution<int> how(0, 9);
  const int kind = how(random);
  if (bytes.empty()) return bytes;
  if (kind == 0) {
    bytes.resize(std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random));
    return bytes;
  }
  std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
  if (kind == 1) {
    bytes.insert(where(random), std::string(1 + random() % 3, static_cast<char>('0' + random() % 10)));
    return bytes;
  }
  const int changes = 1 + static_cast<int>(random() % 4);
  for (int i = 0; i < changes; ++i) bytes[where(random)] = static_cast<char>(random() % 256);
  return bytes;
}

// Runs `read`; returns a description of anything but success or an InputError.
template <typename F>
std::string Outcome(F read) {
  try {
    read();
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    return std::string("unexpected exception: ") + e.what();
  } catch (...) {
    return "unexpected non-standard exception";
  }
  return "";
}

void ExpectWellFormed(const HeightMap& map) {
  ASSERT_EQ(map.z_mm.size(), static_cast<size_t>(map.size_x) * static_cast<size_t>(map.size_y));
  ASSERT_TRUE(map.intensity.empty() || map.intensity.size() == map.z_mm.size());
}

TEST(ReaderFuzz, X3pBytes) {
  X3pWriteOptions options;
  options.date = "2024-01-01T00:00:00+00:00";
  const std::string valid = BuildX3p(SampleMap(6, 4), options);
  std::mt19937 random(4);
  for (int round = 0; round < kRounds; ++round) {
    const std::string bytes = Mutate(valid, random);
    EXPECT_EQ(Outcome([&] { ExpectWellFormed(ParseX3p(bytes, "fuzz.x3p")); }), "") << "round " << round;
  }
}

TEST(ReaderFuzz, X3pMainXml) {
  for (const bool binary : {true, false}) {
    X3pWriteOptions options;
    options.binary = binary;
    options.date = "2024-01-01T00:00:00+00:00";
    const ZipReader original(BuildX3p(SampleMap(6, 4), options), "x");
    std::vector<ZipEntry> entries;
    for (const std::string& name : original.Entries()) entries.push_back({name, original.Read(name, 1 << 20)});
    std::mt19937 random(binary ? 5 : 6);
    for (int round = 0; round < kRounds; ++round) {
      std::vector<ZipEntry> mutated = entries;
      mutated[0].content = Mutate(entries[0].content, random);  // main.xml
      mutated[1].content = Md5Hex(mutated[0].content) + " *main.xml\n";
      const std::string bytes = BuildZip(mutated);
      EXPECT_EQ(Outcome([&] { ExpectWellFormed(ParseX3p(bytes, "fuzz.x3p")); }), "") << "round " << round;
    }
  }
}

TEST(ReaderFuzz, Al3d) {
  const std::string valid = BuildAl3d(SampleMap(6, 4));
  std::mt19937 random(7);
  for (int round = 0; round < kRounds; ++round) {
    // Most of an AL3D is its header: aim half the rounds there.
    std::string bytes = Mutate(valid, random);
    if (round % 2 == 0) {
      bytes = valid;
      for (int i = 0; i < 3; ++i) bytes[random() % 900] = static_cast<char>(random() % 256);
    }
    EXPECT_EQ(Outcome([&] { ExpectWellFormed(ParseAl3d(bytes, "fuzz.al3d")); }), "") << "round " << round;
  }
}

TEST(ReaderFuzz, Sdf) {
  const std::string binary = testing::BinarySdf(3, 2, 1e-6, 2e-6, 1e-9, {1, 2, 3, -4, 5.5, 1e300});
  const std::string ascii = "aISO-1.0\nManufacID = X\nNumPoints = 3\nNumProfiles = 2\nXscale = 1e-6\n"
                            "Yscale = 1e-6\nZscale = 1e-6\nDataType = 7\n*\n1 2 3\n4 5 6\n*\n";
  std::mt19937 random(9);
  for (int round = 0; round < kRounds; ++round) {
    const std::string bytes = Mutate(round % 2 == 0 ? binary : ascii, random);
    EXPECT_EQ(Outcome([&] { ExpectWellFormed(ParseSdf(bytes, "fuzz.sdf")); }), "") << "round " << round;
  }
}

// Other instruments' exports: half the rounds aim at the header, where the sizes and offsets are.
TEST(ReaderFuzz, InstrumentExports) {
  const HeightMap map = SampleMap(6, 4);
  HeightMap all_valid = map;
  for (double& z : all_valid.z_mm) z = std::isfinite(z) ? z : 0.0;
  using Parse = HeightMap (*)(const std::string&, const std::string&);
  const std::vector<std::pair<Parse, std::string>> formats = {
      {ParseSensofarPlu, testing::BuildPlu(map)},        {ParseMetroProDat, testing::BuildMetroPro(map)},
      {ParseWykoOpd, testing::BuildOpd(map)},            {ParseDigitalSurfSur, testing::BuildSur(map)},
      {ParseDigitalSurfSur, testing::BuildSur(map, true)}, {ParseNms, testing::BuildNms(all_valid, -20, 20)},
      {ParseGelSightTmd, BuildGelSightTmd(map)},         {ParseKeyenceVk4, testing::BuildVk4(map)},
      {ParseZygoDatx, testing::BuildDatx(map)},
      {[](const std::string& b, const std::string& n) { return ParseSensofarPlux(b, n); }, testing::BuildPlux(map)}};
  std::mt19937 random(11);
  for (const auto& format : formats) {
    // Named, not a structured binding: clang 14 cannot capture one in the lambda below (C++20 allows it).
    const auto& parse = format.first;
    const auto& valid = format.second;
    for (int round = 0; round < kRounds; ++round) {
      std::string bytes = Mutate(valid, random);
      if (round % 2 == 0) {
        bytes = valid;
        const std::size_t header = std::min<std::size_t>(valid.size(), 600);
        for (int i = 0; i < 3; ++i) bytes[random() % header] = static_cast<char>(random() % 256);
      }
      EXPECT_EQ(Outcome([&] { ExpectWellFormed(parse(bytes, "fuzz")); }), "") << "round " << round;
    }
  }
}

TEST(ReaderFuzz, PcdAndXyz) {
  TempDir dir;
  WritePointCloud(dir / "valid.pcd", HeightMapToCloud(SampleMap(6, 4)));
  const std::string binary = fvm::testing::ReadText(dir / "valid.pcd");
  const std::string ascii =
      "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 2\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n1 2 3\n4 5 6\nnan nan nan\n7 8 9\n1.5 2.5 3.5\n0 0 0\n";
  std::mt19937 random(8);
  for (int round = 0; round < kRounds; ++round) {
    const std::string& valid = round % 2 == 0 ? binary : ascii;
    const auto file = dir.Write("fuzz.pcd", Mutate(valid, random));
    EXPECT_EQ(Outcome([&] { ReadPointCloud(file); }), "") << "round " << round;
    const std::string text = Mutate("# points\nx,y,z\n1,2,3\n4,5,6\n7,8,9e-3\n", random);
    EXPECT_EQ(Outcome([&] { ParseXyz(text, "fuzz.xyz"); }), "") << "round " << round;
  }
}

TEST(ReaderFuzz, Ply) {
  TempDir dir;
  WritePointCloud(dir / "valid.ply", HeightMapToCloud(SampleMap(6, 4)));
  const std::string ply = fvm::testing::ReadText(dir / "valid.ply");
  std::mt19937 random(9);
  for (int round = 0; round < kRounds; ++round) {
    const auto cloud = dir.Write("fuzz.ply", Mutate(ply, random));
    EXPECT_EQ(Outcome([&] { ReadPointCloud(cloud); }), "") << "round " << round;
  }
}

TEST(ReaderFuzz, Tiff) {
  TempDir dir;
  WriteHeightMapImage(dir / "valid.tif", SampleMap(6, 4));
  const std::string tiff = fvm::testing::ReadText(dir / "valid.tif");
  std::mt19937 random(10);
  for (int round = 0; round < kRounds; ++round) {
    const auto image = dir.Write("fuzz.tif", Mutate(tiff, random));
    EXPECT_EQ(Outcome([&] { ExpectWellFormed(ReadHeightMapImage(image)); }), "") << "round " << round;
  }
}

}  // namespace
}  // namespace fvm::imaging
