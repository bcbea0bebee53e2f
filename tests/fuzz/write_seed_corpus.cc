// Writes the binary seeds of tests/fuzz/corpus/ with fvm's own writers (the text seeds there are written by
// hand): small, valid files, so that the fuzzers start from inputs that reach deep into each reader.
//   write_seed_corpus tests/fuzz/corpus
// Heights and clouds come from tests/imaging/surface_samples.h: invalid points, negative and tiny values.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "imaging/io/al3d.h"
#include "imaging/io/gelsight_tmd.h"
#include "imaging/io/height_map_image.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/tile_image.h"
#include "imaging/io/x3p.h"
#include "imaging/io/zip_archive.h"
#include "imaging/point_cloud.h"
#include "tests/support/datx_files.h"
#include "tests/support/instrument_files.h"
#include "tests/support/lext_files.h"
#include "tests/support/surface_samples.h"

namespace {

using fvm::imaging::HeightMap;

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_seed_corpus DIR (tests/fuzz/corpus)\n";
    return 2;
  }
  const std::filesystem::path out = argv[1];
  const HeightMap map = fvm::imaging::testing::SampleMap(6, 4);
  fvm::imaging::X3pWriteOptions x3p;
  x3p.date = "2024-01-01T00:00:00+00:00";  // the same bytes every time
  WriteBytes(out / "x3p" / "binary-d.x3p", fvm::imaging::BuildX3p(map, x3p));
  x3p.binary = false;
  WriteBytes(out / "x3p" / "inline-d.x3p", fvm::imaging::BuildX3p(map, x3p));
  x3p.binary = true;
  x3p.z_type = fvm::imaging::X3pDataType::kInt16;
  x3p.z_increment_mm = 1e-5;
  WriteBytes(out / "x3p" / "binary-i.x3p", fvm::imaging::BuildX3p(map, x3p));
  WriteBytes(out / "al3d" / "sample.al3d", fvm::imaging::BuildAl3d(map));
  // An X3P as a desktop archiver leaves it: zipped around its folder, with macOS clutter beside it.
  {
    x3p.z_type = fvm::imaging::X3pDataType::kFloat64;
    const fvm::imaging::ZipReader zip(fvm::imaging::BuildX3p(map, x3p), "seed.x3p");
    std::vector<fvm::imaging::ZipEntry> entries;
    for (const std::string& name : zip.Entries()) entries.push_back({"scan/" + name, zip.Read(name, 1 << 20)});
    entries.push_back({"__MACOSX/scan/._main.xml", std::string(82, '\x01')});
    entries.push_back({"scan/.DS_Store", std::string(16, '\0')});
    WriteBytes(out / "x3p" / "desktop-zipped.x3p", fvm::imaging::BuildZip(entries));
  }
  // Other instruments' exports, laid out as the instruments write them (tests/support/instrument_files.h).
  namespace instrument = fvm::imaging::testing;
  WriteBytes(out / "plu" / "topography.plu", instrument::BuildPlu(map));
  WriteBytes(out / "plux" / "layer.plux", instrument::BuildPlux(map));
  WriteBytes(out / "metropro" / "format1.dat", instrument::BuildMetroPro(map));
  WriteBytes(out / "opd" / "int16.opd", instrument::BuildOpd(map));
  WriteBytes(out / "sur" / "int32.sur", instrument::BuildSur(map));
  WriteBytes(out / "sur" / "compressed.sur", instrument::BuildSur(map, true));
  fvm::imaging::HeightMap all_valid = map;
  for (double& z : all_valid.z_mm) z = std::isfinite(z) ? z : 0.0;
  WriteBytes(out / "nms" / "height.nms", instrument::BuildNms(all_valid, -20.0, 20.0));
  WriteBytes(out / "tmd" / "v2.tmd", fvm::imaging::BuildGelSightTmd(map));
  WriteBytes(out / "vk4" / "single.vk4", instrument::BuildVk4(map));
  WriteBytes(out / "datx" / "nanometres.datx", instrument::BuildDatx(map));
  WriteBytes(out / "lext" / "ols4000.lext", instrument::BuildLext(map));
  std::filesystem::create_directories(out / "height_map_image");
  fvm::imaging::WriteHeightMapImage(out / "height_map_image" / "sample.tif", map);
  std::filesystem::create_directories(out / "tile_image");
  fvm::imaging::TileImage tile(5, 7);
  for (int r = 0; r < tile.rows(); ++r) {
    for (int c = 0; c < tile.cols(); ++c) tile(r, c) = static_cast<float>(17 * r + 31 * c % 11);
  }
  fvm::imaging::WriteTileImage(out / "tile_image" / "u8.png", tile, fvm::imaging::TilePixelType::kUint8);
  fvm::imaging::WriteTileImage(out / "tile_image" / "u16.tif", tile, fvm::imaging::TilePixelType::kUint16);
  fvm::imaging::WriteTileImage(out / "tile_image" / "float.tif", tile, fvm::imaging::TilePixelType::kFloat);
  std::filesystem::create_directories(out / "pcd");
  std::filesystem::create_directories(out / "ply");
  const fvm::imaging::PointCloud organised = fvm::imaging::HeightMapToCloud(fvm::imaging::testing::SampleMap(3, 2));
  const fvm::imaging::PointCloud loose = fvm::imaging::MakeUnorganisedCloud({{0.1, -200.25, 1e-9}, {150.000001, 3, -0.5}});
  fvm::imaging::WritePointCloud(out / "pcd" / "organised-binary.pcd", organised);
  fvm::imaging::WritePointCloud(out / "pcd" / "loose-binary.pcd", loose);
  fvm::imaging::WritePointCloud(out / "ply" / "organised-binary.ply", organised);
  fvm::imaging::WritePointCloud(out / "ply" / "loose-binary.ply", loose);
  return 0;
}
