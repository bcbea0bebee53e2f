#pragma once
// The normalised cross-correlation of two tiles' overlap at every whole-pixel offset of a window at once, by
// Fourier transforms (Padfield 2012, "Masked object registration in the Fourier domain"): the overlap's size and
// its valid pixels change with the offset, and the NCC over it is what tells the true step of a repeating pattern
// from a step that matches the pattern only. Computed on a pyramid level, so that the whole plausible range of a
// pair's steps is searched in a few milliseconds; its peaks are the candidates of the wide search.
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>
#include <vector>
#include <opencv2/core.hpp>

#include "imaging/tile_prefilter.h"

namespace fvm::imaging::detail {

struct LandscapePeak {
  Eigen::Vector2i offset_px = Eigen::Vector2i::Zero();  // b's top-left in a's frame, full-resolution pixels
  double ncc = 0.0;                                     // on the pyramid level
  int pixels = 0;                                       // of the overlap, full-resolution pixels
  double fall = 1.0;  // how much the NCC falls 4 level pixels away along x and y, the least of the four
};
struct NccLandscape {
  std::vector<LandscapePeak> peaks;  // highest first
  double unmoved_ncc = -2.0;         // at offset 0 (the tiles one on the other), wherever the window lies; -2: none
};

// The local maxima (over 3 x 3 offsets of the level) of the overlap NCC of the prepared tiles a and b (whole
// tiles, the same band, on the pyramid level whose pixel is `scale` full-resolution pixels: AreaDownsample) for
// offsets within `search` (per axis, full-resolution pixels) of `nominal`; at most `peaks`, highest first. Offsets whose overlap is smaller than
// `min_pixels` (full resolution) are left out: a sliver of an overlap correlates well by chance.
NccLandscape OverlapNccPeaks(const Prepared& a, const Prepared& b, const Eigen::Vector2d& nominal,
                             const Eigen::Vector2d& search, int scale, int min_pixels, int peaks);

// A tile (or its prepared values) on the level: `scale` x `scale` blocks averaged.
cv::Mat AreaDownsample(const cv::Mat& tile, int scale);
// The pyramid level's scale for tiles of this size: halved while the smaller side stays at least 128 px, at
// most 4 (the matching band's 2 px smoothing loses little at 2; fine noise texture needs full resolution).
int LandscapeScale(int cols, int rows);

}  // namespace fvm::imaging::detail
