#pragma once
// Synthetic tile sets with a recorded truth, for testing and benchmarking registration: tiles cut at sub-pixel
// positions from one random texture (a sum of sinusoids, so that every sample is exact, with no interpolation),
// with stage errors, uneven illumination and sensor noise.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/tile_registration.h"

namespace fvm::artefacts {

// What the camera sees of the part and how: the part's texture (a sum of `components` sinusoids with frequencies
// up to max_frequency cycles / px and a 1/f amplitude spectrum, mean `level`, standard deviation `contrast`, in
// image counts), the lens' vignetting and the sensor's noise.
struct TileCameraOptions {
  int components = 48;
  double max_frequency = 0.2;
  // Directions of the waves (their crests' normals, from +x towards +y of the pixel frame): uniform in
  // [wave_angle_deg, wave_angle_deg + wave_spread_deg). The default covers every direction; a narrow spread is a
  // machined lay (marks across wave_angle_deg), and a spread of 0 a texture that does not change along the marks.
  double wave_angle_deg = 0.0;
  double wave_spread_deg = 360.0;
  double level = 30000.0, contrast = 6000.0;
  double vignetting = 0.3;  // the gain falls by this fraction from the tile's centre to its corners
  double noise = 0.03;      // sensor noise, a fraction of `contrast`
  // Shot noise: a count is this many photo-electrons, so a pixel of c counts scatters by sqrt(c / it) counts on
  // top of `noise`; 0 leaves it out.
  double electrons_per_count = 0.0;
  // Blobs instead of a texture that fills the field: only the crests of the sum of waves above 1.5 of its
  // standard deviation show, as bright spots of `contrast` scale on a dark `level` (a sparse sample).
  bool blobs = false;
  void Check() const;       // throws std::invalid_argument
};

// One textured part and one camera: Photograph() images it with the first pixel's centre at any sub-pixel point
// of the part's pixel frame (x right, y down).
class TileScene {
 public:
  TileScene() = default;  // no texture
  // Draws the texture from `random`.
  TileScene(const TileCameraOptions& options, std::mt19937_64& random);
  // A width x height tile whose pixel (0, 0) samples the texture at top_left_px; noise drawn from `random`.
  imaging::TileImage Photograph(const Eigen::Vector2d& top_left_px, int width, int height,
                                std::mt19937_64& random) const;
  // The same with the camera turned or scaled against the scene: pixel (x, y) samples the texture at
  // origin_px + axes (x, y). A sum of waves stays separable in x and y under any affine map, so this costs the same.
  imaging::TileImage Photograph(const Eigen::Matrix2d& axes, const Eigen::Vector2d& origin_px, int width, int height,
                                std::mt19937_64& random) const;

 private:
  struct Wave {
    double fx, fy, phase, amplitude;
  };
  TileCameraOptions options_;
  std::vector<Wave> waves_;
};

struct TileSynthesisOptions {
  int rows = 3, cols = 3;
  int width = 256, height = 256;  // px
  double overlap = 0.2;           // nominal fraction shared by neighbours
  // Stage error: every tile's true position departs from the grid by a normal draw of this size per axis (px).
  double position_sigma_px = 1.5;
  TileCameraOptions camera;
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct SynthesizedTiles {
  std::vector<imaging::TileImage> images;      // scan order: column by column, top to bottom
  std::vector<imaging::GridTile> tiles;        // rows, cols and nominal (grid) positions
  std::vector<Eigen::Vector2d> truth_px;       // true top-left corners, tile 0 at its nominal position
  TileScene scene;  // what the tiles were photographed from: Photograph(p, ...) is the scene at p of the tiles' frame
};

SynthesizedTiles SynthesizeTiles(const TileSynthesisOptions& options);

}  // namespace fvm::artefacts
