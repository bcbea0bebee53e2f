#pragma once
// The real strip of ../shared/realdata/tiles/starrynight (10 camera tiles of 594 x 929 px, one row) with the
// positions Fiji's Grid/Collection stitching registered: for the test and the benchmark. Empty when ../shared is
// absent (a user's clone), so that both skip.

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging::testing {

struct RealStrip {
  std::vector<TileImage> images;
  std::vector<GridTile> tiles;               // row 0, col i, nominal from tile_config.txt
  std::vector<Eigen::Vector2d> fiji_px;      // tile_config.registered.txt
};

// Lines "N.tif; ; (x, y)" of a Fiji tile configuration, in tile order 1..10.
inline std::vector<Eigen::Vector2d> ReadFijiConfiguration(const std::filesystem::path& path) {
  std::ifstream in(path);
  const std::regex line(R"(^(\d+)\.tif;\s*;\s*\(\s*([-0-9.eE+]+)\s*,\s*([-0-9.eE+]+)\s*\))");
  std::vector<Eigen::Vector2d> out(10, Eigen::Vector2d::Constant(NAN));
  std::string text;
  std::smatch m;
  while (std::getline(in, text)) {
    if (!std::regex_search(text, m, line)) continue;
    const int k = std::stoi(m[1]) - 1;
    if (k >= 0 && k < 10) out[static_cast<size_t>(k)] = {std::stod(m[2]), std::stod(m[3])};
  }
  return out;
}

inline RealStrip LoadStarrynight() {
  RealStrip strip;
  const std::filesystem::path dir = std::filesystem::path(FVM_REALDATA_DIR) / "tiles" / "starrynight";
  if (!std::filesystem::exists(dir / "tile_config.registered.txt")) return strip;
  const std::vector<Eigen::Vector2d> nominal = ReadFijiConfiguration(dir / "tile_config.txt");
  strip.fiji_px = ReadFijiConfiguration(dir / "tile_config.registered.txt");
  for (int i = 0; i < 10; ++i) {
    strip.images.push_back(ReadTileImage(dir / (std::to_string(i + 1) + ".tif")));
    strip.tiles.push_back({0, i, nominal[static_cast<size_t>(i)]});
  }
  return strip;
}

}  // namespace fvm::imaging::testing
