#pragma once
// Fusing registered tiles into one image: a mosaic of intensity tiles, or one height map of height tiles. Each
// tile is resampled at its sub-pixel position (Lanczos-4) and blended with a weight that falls linearly to zero at
// its border (feathering), so that the seams between tiles with different shading or height offsets do not show.
// Invalid pixels (NaN) of a tile carry no weight: another tile's valid pixel there fills the hole.
//
// Pixel frame as in tile_registration.h: x to the right, y down, positions are the tiles' top-left pixels.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "imaging/height_map.h"
#include "imaging/io/tile_image.h"

namespace fvm::imaging {

struct Mosaic {
  TileImage image;                                      // NaN where no tile reaches
  Eigen::Vector2d origin_px = Eigen::Vector2d::Zero();  // where the mosaic's pixel (0, 0) lies in the tiles' frame
};

// Throws std::invalid_argument when there are no tiles, the counts differ, or a position is not finite.
// `on_tile_fused(done, total)`, when given, is called after each tile (for a progress line; same thread).
Mosaic FuseTiles(const std::vector<TileImage>& tiles, const std::vector<Eigen::Vector2d>& positions_px,
                 const std::function<void(int done, int total)>& on_tile_fused = {});

// The mosaic as a height map in the stage frame (+Y up): tile pixels hold heights in mm, `pixel_mm` is their
// size, and `first_centre_mm` is the stage position of the centre of the tile at position (0, 0).
HeightMap MosaicToHeightMap(const Mosaic& mosaic, int tile_width, int tile_height, double pixel_mm,
                            const Eigen::Vector2d& first_centre_mm);

}  // namespace fvm::imaging
