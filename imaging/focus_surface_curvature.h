#pragma once
// The surface's own curvature, for the heights' curvature corrections (focus_window_curvature.h,
// focus_steep_curvature_bias.h): the local mean of the height map's Laplacian over a scale much larger than a
// window. The Laplacian's mean over a Gaussian of sigma S is the heights' noise seen through a band-pass near 1/S (the
// Laplacian of the Gaussian) divided by S^2, so its noise falls steeply with S: over 14 px it is 2-10 % of a
// calotte's curvature on ../shared/bench/focusgen.py's stacks (sphere of 0.4 mm, 1 um pixels; 2 px texture at NA 0.9
// the worst), where a 6 px mean had to be shrunk by half in the bottoms that needed all of the correction.
// A sharp bend (a calotte's rim) is no curvature to spread, and its ridge in the Laplacian of the map is wide (a 9 px
// window straddling the rim, then the 2 px smoothing: 10-20 px at NA 0.9) while the bends' own test
// (focus_height_maps.cc) flags its top only, in patches where the heights are noisy: a mean that left out only the
// flagged points, or their neighbours within 3-12 px, still read the rim's ridge (-0.4 to -2 times the bottom's
// curvature within 15 px of the rim, and 15-25 % too little in the bottom). So the ridge is found at the
// curvature's own scale: where the Laplacian's local mean over kRidgeScalePx departs from a first large-scale mean
// (the flagged bends left out) by more than kRidgeCut times its typical departure (a robust scale, Huber 1981). The
// points within kRidgeReachPx of a bend or the ridge are left out of the final mean (a normalised convolution,
// Knutsson and Westin 1993), and a point whose surroundings they leave with less than half the Gaussian's weight has
// no curvature (NaN): the band along a rim, where a mean would mix both sides, but not a lone ridge of the noise in
// a wide bottom. On focusgen.py (NA 0.3-0.9, 0.7-2 px texture) the known curvature then reads 0.97-1.03 of the
// truth in bottoms and walls up to 25 px from the rim, and the band left unknown reaches 8-15 px either side of it.
// Used by focus_height_maps.cc; the ridge test by focus_slope_beside_bends.cc too.

#include <opencv2/core.hpp>

#include "imaging/focus_map_pool.h"

namespace fvm::imaging {

// The sigma (px) of the curvature's local mean; the reach (px) of the bends the roughness found in the first mean;
// the ridge's scale (sigma, px) and cut (times the typical departure); the reach (px) of bends and ridge in the
// final mean.
inline constexpr double kSurfaceCurvaturePx = 14.0;
inline constexpr double kCurvatureBendReachPx = 3.0;
inline constexpr double kRidgeScalePx = 4.0;
inline constexpr float kRidgeCut = 3.0f;
inline constexpr double kRidgeReachPx = 8.0;

// Into `curvature`: the local mean of `laplacian` (mm per px^2) over kSurfaceCurvaturePx, weighted by `weight` (a
// point's trust, 0 in holes and at the bends), with the bends (`bends`: 1 at a bend's points, else 0) and the ridge
// left out as above; NaN where unknown. All maps row-major, of the size of `pool`'s maps (which the function takes
// its scratch maps from), filtered in stripes of rows (MapPool::Pass).
void SurfaceCurvature(MapPool& pool, const float* laplacian, const float* weight, const float* bends,
                      float* curvature);

// A sharp bend's ridge in a Laplacian (`laplacian`, weighted by `weight`): the square of its local mean over
// kRidgeScalePx less `baseline` (the surface's own curvature there; nothing when empty), and the cut beyond which a
// point lies on the ridge, kRidgeCut^2 times that square's typical size over the weighted points (a robust scale,
// TypicalSquare). SurfaceCurvature's ridge test, shared by the slope beside a bend (focus_slope_beside_bends.h).
struct Ridge {
  cv::Mat square;
  float cut = 0.0f;
};
Ridge FindRidge(const cv::Mat& laplacian, const cv::Mat& weight, const cv::Mat& baseline, MapPool& pool);

}  // namespace fvm::imaging
