#pragma once
// Dense sub-pixel correspondences in the overlap of two tiles: the raw pixel of a and the raw pixel of b that show
// the same point of the part, on a grid over the overlap, by pyramidal Lucas-Kanade optical flow (Bouguet 2001, as
// OpenCV implements it) of the high-passed tiles, kept when tracking back from b lands within a tenth of a pixel of
// where it started. What a rigid registration averages away (the field distortion, field_distortion.h) is in the
// way these pairs of pixels depart from one translation.
//
// Pixel frame as in tile_registration.h: x right, y down, an offset is b's top-left corner in a's frame.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "imaging/field_distortion.h"
#include "imaging/io/tile_image.h"

namespace fvm::imaging {

struct CorrespondenceOptions {
  int grid_step_px = 8;    // spacing of the grid of points over the overlap
  int window_px = 15;      // Lucas-Kanade window (odd)
  int pyramid_levels = 3;  // reaches 4 (2^levels) window half-widths: the field's pull between two tiles' views
  double max_round_trip_px = 0.1;  // a -> b -> a must land this close to the start
  double highpass_sigma_px = 8.0;  // shading and vignetting out before tracking
  // false: no tracker; each point refined from where the guess puts it, kept when it settles within half a pixel
  // of there. For a guess good to a fraction of a pixel (the field and positions of an earlier round), where the
  // tracker's search and its round trip only repeat what the guess already knows.
  bool track = true;
  void Check() const;             // throws std::invalid_argument
};

struct PairCorrespondences {
  int a = 0, b = 0;  // tile indices
  std::vector<Eigen::Vector2d> a_px, b_px;  // raw pixels that see the same point
  int tried = 0;     // grid points in the overlap
  // What each point sees of the field: d averaged over the window it was matched on (MatchingKernel), in both
  // tiles alike. All 0 (the pixel itself) for correspondences known exactly.
  FieldKernel kernel;
};

// The kernel the matching averages the field over: the refinement's window of window_px x window_px pixels, uniform
// in expectation over a texture (the translation it fits weighs each pixel by its gradients), after the 1 px
// Gaussian both tiles are smoothed with.
FieldKernel MatchingKernel(const CorrespondenceOptions& options);

// Points of a on a grid over the overlap that b at `offset_px` shares with it, inset so that both views stay inside
// their tiles whatever `guess` (the field believed so far; the identity at first) moves them; each point's start in b
// is where the guess puts it: u_b + d(u_b) = u_a + d(u_a) - offset, and b's window is warped to a's view of it by the
// guess's local map (I + grad d(u_b))^-1 (I + grad d(u_a)): the field stretches the two views differently, and a
// translation fitted to windows that differ by a stretch is biased at second order in it. Empty when the overlap is
// too small for a window.
PairCorrespondences MatchOverlap(const TileImage& a, const TileImage& b, int a_index, int b_index,
                                 const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                 const CorrespondenceOptions& options = {});

// Many overlaps of one tile set at once, on OpenCV's thread pool; each tile prepared once.
struct OverlapToMatch {
  int a = 0, b = 0;
  Eigen::Vector2d offset_px = Eigen::Vector2d::Zero();
};
std::vector<PairCorrespondences> MatchOverlaps(const std::vector<TileImage>& images,
                                               const std::vector<OverlapToMatch>& overlaps,
                                               const FieldDistortion& guess, const CorrespondenceOptions& options = {});

// The tiles as the matching takes them (high-passed, with their gradients), prepared once, on OpenCV's thread pool,
// for several rounds of matching on one tile set: preparing a tile costs more than matching its overlaps. An opaque
// handle (OpenCV's images stay in the .cc), cheap to copy.
struct PreparedTileSet;
struct PreparedTiles {
  std::shared_ptr<const PreparedTileSet> set;
  int size = 0;
};
PreparedTiles PrepareTilesForMatching(const std::vector<TileImage>& images, const CorrespondenceOptions& options = {});
// MatchOverlaps on tiles prepared before (with the same highpass_sigma_px).
std::vector<PairCorrespondences> MatchPreparedOverlaps(const PreparedTiles& tiles,
                                                       const std::vector<OverlapToMatch>& overlaps,
                                                       const FieldDistortion& guess,
                                                       const CorrespondenceOptions& options = {});

}  // namespace fvm::imaging
