#pragma once
// The slope a window's centroid correction multiplies (focus_window_centroid.h), read on the pixel's own side of a
// sharp bend. The map's slope is that of its 2 px local mean, which beside a calotte's rim reads the rim's dip (the
// heights of windows straddling the rim, pulled down by the wall's pixels) and the wall beyond it: on
// ../shared/bench/focusgen.py's stacks at NA 0.9, 0.10-0.13 step per px 3-4 px outside the rim where the face is level
// (0.005). Times sharpness centroids pulled towards the rim (the wall's texture is 7-20 times sharper than the level
// face's there: focusgen.py's rendering brightens a tilted face's in-focus contour, which real optics do not,
// docs/commands/focus.md; the slope read across the bend is wrong in either case), that raised a ring 3-8 px outside
// the rim by +0.08 to +0.20 step (coverage 68-85 % with a 2 px texture). Yet the wall's pixels in such a window hardly
// move its peak there: without the correction the ring reads -0.02 step. Their heights lie 0.5-1.5 step below the level
// face's, beyond the half-width of a focus curve at NA 0.9, so their curves form a bump of their own instead of
// shifting the face's (the sum of narrow peaks peaks at the tallest, not at their weighted mean: the mean-shift view of
// a mixture, Fukunaga and Hostetler 1975). So within kRidgeReachPx of the bend's ridge (found as SurfaceCurvature finds
// it, focus_surface_curvature.h) a point takes the slope of the nearest point beyond that reach: the stencil taken from
// the smooth side of a discontinuity, as in essentially non-oscillatory schemes (Harten et al. 1987). That point is on
// the pixel's own side when its plane (its height and slope), extended to the pixel, meets the pixel's own height
// within kOwnSideSteps z-steps; where it does not (the nearest point lies across the bend, as where the image's edge
// cuts off the pixel's own side, or the pixel lies on the bend's top, whose heights are neither side's) the map's own
// slope is kept. Where the focus curves are wide (NA 0.6 and below: the wall's pixels lie within a curve's half-width
// and do pull the peak, as the first-order correction has it: the ring there reads -0.01 to +0.02 step with the map's
// slope) the map's slope is kept: the caller passes the share of the own side's slope by the stack's narrow curves
// (NarrowCurveShare, focus_steep_curvature_bias.h). Used by focus_variation.cc.

#include "imaging/focus_map_pool.h"

namespace fvm::imaging {

// How far (z-steps) the nearest point's plane may miss a point's own height for its slope to be taken.
inline constexpr double kOwnSideSteps = 0.3;

// Into `beside_x`, `beside_y`: the slope (`slope_x`, `slope_y`, height change per px along x and y, of the heights'
// 2 px local mean `smooth`), moved beside the bends by `share` (0 to 1) of the way to the own side's slope as above;
// elsewhere, and everywhere for share 0, the slope itself. `valid` is 1 at the map's points, 0 in its holes;
// `step_mm` the stack's z-step. All maps row-major, of the size of `pool`'s maps (which the function takes its
// scratch maps from), filtered in stripes of rows (MapPool::Pass).
void SlopeBesideBends(MapPool& pool, const float* smooth, const float* slope_x, const float* slope_y,
                      const float* valid, double step_mm, double share, float* beside_x, float* beside_y);

}  // namespace fvm::imaging
