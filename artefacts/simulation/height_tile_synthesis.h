#pragma once
// Height-map tiles of an artefact as a focus-variation instrument exports them, with a recorded truth: one map of
// the whole artefact is rendered (artefacts/calotte_surface.h), with the face's roughness frozen into it as the
// only texture between the calottes and the steep flanks invalid (NaN); tiles are cut from it on a grid, each off
// its grid position by a whole-pixel stage error, each with measurement noise of its own.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/calotte_surface.h"
#include "imaging/io/tile_image.h"
#include "imaging/tile_registration.h"

namespace fvm::artefacts {

struct HeightTileOptions {
  int rows = 0, cols = 0;  // 0: as many as cover the whole map (the part beyond it is invalid)
  int size = 256;          // px, square tiles
  double overlap = 0.2;
  double position_sigma_px = 1.5;  // stage error per axis, rounded to whole pixels
  double noise_mm = 0.0001;        // each tile's own height noise (0.1 um, the 10x lens' resolution)
  CalotteSurfaceOptions surface = [] {
    CalotteSurfaceOptions o;
    o.dx_mm = o.dy_mm = 0.01;
    o.noise_sigma_mm = 0.0005;    // the face's roughness: frozen into the map, so the tiles share it
    o.max_slope_deg = 50.0;       // the steeper flanks come out invalid, as with a 10x lens
    o.missing_fraction = 0.002;   // and a few dropouts
    return o;
  }();
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct SynthesizedHeightTiles {
  CalotteSurface surface;                   // the whole map and the true calottes, in mm
  std::vector<imaging::TileImage> images;   // heights in mm, NaN where invalid; scan order, column by column
  std::vector<imaging::GridTile> tiles;     // rows, cols and nominal (grid) positions, px
  std::vector<Eigen::Vector2d> truth_px;    // true top-left corners, tile 0 at 0, 0
  // Where the stage was told to put each tile's centre; the first tile has no error, so its entry is also true.
  std::vector<Eigen::Vector2d> nominal_centre_mm;
};

SynthesizedHeightTiles SynthesizeHeightTiles(const Artefact& artefact, const HeightTileOptions& options);

}  // namespace fvm::artefacts
