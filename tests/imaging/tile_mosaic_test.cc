// Fusing registered tiles: the mosaic reproduces the scene the tiles were cut from, and the height map built
// from it sits in the stage frame.

#include "imaging/tile_mosaic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "artefacts/simulation/tile_synthesis.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging {
namespace {

// RMS of mosaic - scene over the mosaic's valid pixels, in units of the texture's contrast.
double RelativeRmsError(const Mosaic& mosaic, const artefacts::SynthesizedTiles& tiles, double contrast) {
  std::mt19937_64 unused(0);
  const TileImage scene = tiles.scene.Photograph(mosaic.origin_px, static_cast<int>(mosaic.image.cols()),
                                                 static_cast<int>(mosaic.image.rows()), unused);
  double sum = 0.0;
  long n = 0;
  for (Eigen::Index i = 0; i < scene.size(); ++i) {
    const float m = mosaic.image.data()[i];
    if (std::isnan(m)) continue;
    sum += std::pow(m - scene.data()[i], 2);
    ++n;
  }
  EXPECT_GT(n, 0);
  return std::sqrt(sum / static_cast<double>(n)) / contrast;
}

TEST(TileMosaic, RegisteredTilesFuseIntoTheScene) {
  artefacts::TileSynthesisOptions options;
  options.seed = 4;
  options.camera.vignetting = 0.0;  // the scene itself, so that the mosaic can be compared with it
  options.camera.noise = 0.0;
  const auto tiles = artefacts::SynthesizeTiles(options);
  const RegistrationResult registered = RegisterTileGrid(tiles.images, tiles.tiles, {});
  const Mosaic mosaic = FuseTiles(tiles.images, registered.positions.positions_px);
  // The mosaic spans the tiles' true extent (3 x 3 tiles of 256 px at 204.8 px steps, each off by the stage
  // error), plus the pixel that the sub-pixel remainder reaches into, and up to a pixel at either end where the
  // frame rounds out to whole pixels (0.01 px for the registration error).
  Eigen::Vector2d lo = tiles.truth_px[0], hi = lo;
  for (const Eigen::Vector2d& p : tiles.truth_px) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector2d extent = hi - lo + Eigen::Vector2d(256, 256);
  for (const auto& [size, span] : {std::pair{mosaic.image.cols(), extent.x()}, {mosaic.image.rows(), extent.y()}}) {
    EXPECT_GE(static_cast<double>(size), span + 1 - 0.01);
    EXPECT_LT(static_cast<double>(size), span + 3 + 0.01);
  }
  for (size_t i = 0; i < tiles.tiles.size(); ++i) {
    const Eigen::Vector2d centre = registered.positions.positions_px[i] - mosaic.origin_px + Eigen::Vector2d(128, 128);
    EXPECT_FALSE(std::isnan(mosaic.image(std::lround(centre.y()), std::lround(centre.x())))) << i;
  }
  // Lanczos-4 resampling attenuates texture near 0.2 cycles / px by a few per cent at half-pixel shifts; with the
  // registration's 0.005 px that leaves 0.8 % of the contrast (measured), bounded at 2 %. Tiles fused where the
  // stage put them (1.5 px off) blur and double the texture: 41 %.
  const double registered_error = RelativeRmsError(mosaic, tiles, options.camera.contrast);
  std::vector<Eigen::Vector2d> stage;
  for (const auto& t : tiles.tiles) stage.push_back(t.nominal_px);
  const double stage_error = RelativeRmsError(FuseTiles(tiles.images, stage), tiles, options.camera.contrast);
  std::printf("mosaic rms error: %.4f of the contrast registered, %.3f at the stage positions\n", registered_error,
              stage_error);
  EXPECT_LT(registered_error, 0.02);
  EXPECT_GT(stage_error, 0.2);
}

TEST(TileMosaic, HeightMapSitsInTheStageFrame) {
  // Two tiles of a tilted plane z = 0.001 X - 0.002 Y (mm), the second 100 px to the right and 30 px down, its
  // pixels taken where the stage frame says they are; the fused map must give the plane at its own coordinates.
  const double pixel = 0.002;
  const Eigen::Vector2d first_centre(10.0, 20.0);
  const int w = 64, h = 48;
  const auto plane = [](double x, double y) { return 0.001 * x - 0.002 * y; };
  std::vector<TileImage> tiles;
  const std::vector<Eigen::Vector2d> positions = {{0, 0}, {100, 30}};
  for (const Eigen::Vector2d& p : positions) {
    TileImage tile(h, w);
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const double x = first_centre.x() + (p.x() + c - (w - 1) / 2.0) * pixel;
        const double y = first_centre.y() - (p.y() + r - (h - 1) / 2.0) * pixel;
        tile(r, c) = static_cast<float>(plane(x, y));
      }
    }
    tiles.push_back(tile);
  }
  const HeightMap map = MosaicToHeightMap(FuseTiles(tiles, positions), w, h, pixel, first_centre);
  EXPECT_EQ(map.size_x, 165);
  EXPECT_EQ(map.size_y, 79);
  int valid = 0;
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix) {
      const float z = map.at(ix, iy);
      if (std::isnan(z)) continue;
      ++valid;
      EXPECT_NEAR(z, plane(map.x0_mm + ix * pixel, map.y0_mm + iy * pixel), 1e-6) << ix << "," << iy;
    }
  }
  EXPECT_EQ(valid, 2 * w * h);  // whole-pixel positions: every tile pixel once, nothing between the tiles
}

TEST(TileMosaic, RejectsMismatchedInput) {
  EXPECT_THROW(FuseTiles({}, {}), std::invalid_argument);
  EXPECT_THROW(FuseTiles({TileImage::Zero(8, 8)}, {}), std::invalid_argument);
  EXPECT_THROW(FuseTiles({TileImage::Zero(8, 8)}, {Eigen::Vector2d(NAN, 0)}), std::invalid_argument);
}

}  // namespace
}  // namespace fvm::imaging
