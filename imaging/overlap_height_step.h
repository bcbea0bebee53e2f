#pragma once
// The z step between two registered height-map tiles, from their overlap.

#include <Eigen/Core>

#include "imaging/io/tile_image.h"

namespace fvm::imaging {

// Height-map tiles: how much higher a shows the part than b where they overlap, mean(a(p) - b(p - offset)) over the
// overlap's valid pixels at a registered offset (b sampled bilinearly), with the variance of that mean from the
// differences' scatter. Between two tiles of a stitched scan it is the stage's z step between them, seen by the
// part. pixels == 0 when no valid pixel overlaps.
struct HeightStep {
  double mean = 0.0, variance = 0.0;
  int pixels = 0;
};
HeightStep OverlapHeightStep(const TileImage& a, const TileImage& b, const Eigen::Vector2d& offset_px);

}  // namespace fvm::imaging
