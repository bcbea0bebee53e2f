#pragma once
// The height a window's focus curve gives on a curved surface is not the height at the window's centre: the window
// sums the focus curves of its pixels, each in focus at its own height, and where the curve is wide against the
// spread of those heights the summed curve peaks at their weighted mean. Over a quadratic surface that mean is the
// centre's height plus (sigma^2 / 2) times the Laplacian, sigma^2 the variance of the window's weights along an axis
// (the second-order term of a Gaussian smoothing's bias, e.g. Lindeberg 1994). In a calotte's bottom
// (../shared/bench/focusgen.py, sphere radius 0.4 mm, 9 px window: 3.6 px^2 x Laplacian) that is +0.017 of a 1 um
// step, the bias its heights showed at NA 0.3-0.4 (+0.015-0.019 with a 0.7-1 px texture). Knowing the surface's
// curvature (focus_surface_curvature.h: the local mean of the height map's Laplacian over 14 px, clear of the
// heights' noise; unknown near a sharp bend) and each height's window, the shift is removed. Used by
// focus_variation.cc.

#include <vector>

#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {

// The variance (px^2, along one axis) of the weights a window's focus measure gives the pixels around its centre:
// the window's taps, widened by the measure's pre-filter (focus_stack_curves.h).
double WindowWeightVariancePx2(const WindowCurves& window);

// Moves each finite height z_mm[i] by -(sigma^2 / 2) x laplacian[i] (mm per px^2), sigma^2 that of the window it came
// from (window_px[i], one of `windows`; heights from no such window, or with a NaN Laplacian, are left alone). Maps
// row-major, width x height.
void CorrectWindowCurvature(int width, int height, bool parallel, const std::vector<WindowCurves>& windows,
                            const std::vector<float>& window_px, const float* laplacian, std::vector<double>& z_mm);

}  // namespace fvm::imaging
