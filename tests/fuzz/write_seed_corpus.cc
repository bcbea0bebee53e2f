// Writes the binary seeds of tests/fuzz/corpus/ with fvm's own writers (the text seeds there are written by
// hand): small, valid files, so that the fuzzers start from inputs that reach deep into each reader.
//   write_seed_corpus tests/fuzz/corpus
// Heights and clouds come from tests/imaging/surface_samples.h: invalid points, negative and tiny values.

#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "imaging/io/al3d.h"
#include "imaging/io/height_map_image.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/tile_image.h"
#include "imaging/io/x3p.h"
#include "imaging/point_cloud.h"
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
