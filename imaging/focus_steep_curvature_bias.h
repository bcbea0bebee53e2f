#pragma once
// On a steep curved wall, where the stack's focus curves are narrow and sharp-topped, a window's height lies above the
// surface by a bias that grows with the wall's curvature and, beyond a slope of about a quarter of a step per pixel,
// with its slope. Measured on ../shared/bench/focusgen.py's calotte (1 um pixels and steps, 9 px window) at NA 0.9
// with a 0.8 um diffraction floor: +0.005 step at slopes below 0.21 step/px, +0.05 at 0.3, +0.09 at 0.36-0.39, twice
// that on a sphere of half the radius, none on a plane of the same slope; it grows with the window's width (+0.04,
// +0.06, +0.105 step at 0.3-0.36 step/px for windows of sigma 1.5, 2.7 and 4.5 px: linearly, not as its square, so it
// is no mean of the heights over the window, see focus_window_curvature.h). It needs both a blur that grows linearly
// from its floor (sigma = sigma0 + k |dz|, the geometric cone: a transformed focus curve with a V-shaped top) and
// light scattered onto a pixel from its neighbours at other heights: the same scene rendered with a smooth waist
// (sigma^2 = sigma0^2 + (k dz)^2) or with each pixel blurred by its own defocus only (focusgen.py --model gather)
// shows none. The depth of field alone does not tell where it arises: at NA 0.9 a 0.3 and a 0.8 um floor give
// focus curves of the same width (neighbours' shoulder 0.61-0.65 of the peak) and walls biased by +0.01 and +0.06
// step. The curve's shape does: the ratio of the transformed measure's rise two images from the peak to its rise
// one image away (4 for the parabola of a smooth waist, 2 for a V; 2.55-2.75 at NA 0.9 with a 0.8 um floor,
// 3.56-3.73 with a 0.3 um floor). So the stack's typical focus curve, on its gentle parts, says how much of the bias
// to remove: all of it where the curves are narrow (shoulder below kNarrowShoulderFull) and V-topped (ratio below
// kCuspFull), none where either is wide or round. Within reach of a sharp bend (a calotte's rim), where the map's
// curvature is unknown, the heights are left alone and the bias's size, from the curvature around, goes to u_z.
// Caution: the light scattered in is focusgen.py's rendering (each point spread by a Gaussian of sigma0 + k |dz|),
// which brightens a tilted face's in-focus contour; real optics image a uniform tilted face uniformly (backward ray
// tracing and scalar wave optics, docs/commands/focus.md), so this bias may be the generator's, to be re-judged on
// real stacks of curved walls. Used by focus_variation.cc.

#include <cstddef>
#include <vector>

#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {

// The shares are calibrated on focusgen.py seeds 11 and 12 over 13 conditions (NA 0.3-0.9, floor 0.3-0.8 um,
// texture correlation 0.7-2 px; tests/bench/focus_conditions.py) and checked on seeds 13 and 14. Shoulder (the sum
// of the best image's neighbours over the peak, above the floor): 0.61-0.74 at NA 0.9 with a 0.7-1 px texture,
// 1.07-1.24 with 2 px, 1.51-1.89 at NA 0.3-0.6. Shape ratio: 2.55-3.22 at NA 0.9 with a 0.6-0.8 um floor, 3.56-3.73
// with 0.3 um.
inline constexpr double kNarrowShoulderFull = 1.3, kNarrowShoulderNone = 1.5;
inline constexpr double kCuspFull = 3.0, kCuspNone = 3.5;
// The bias: kSteepBiasPx times the window's weights' sigma (px) times the surface's Laplacian (mm per px^2), at
// full share from a slope of kSteepRampEndSteps steps per px, rising linearly from kSteepRampStartSteps (6.75 px x
// 2.67 px = 18 px^2 for the 9 px window). The ramp starts where the bias does: with this term off, NA 0.9 walls with
// a 0.6-0.8 um floor read -0.01 to -0.02 step at 0.20-0.25 step/px and cross zero at 0.25-0.28 (focusgen.py seeds 11,
// 12; none at all below 0.4 when each pixel is blurred by its own defocus only, --model gather); a ramp from 0.22
// took 0.01-0.03 step off there (walls at 0.2-0.3 step/px -0.023 step on average, -0.015 from 0.28).
inline constexpr double kSteepBiasPx = 6.75;
inline constexpr double kSteepRampStartSteps = 0.28, kSteepRampEndSteps = 0.36;

// The typical focus curve of a stack: medians over a sample of the valid peaks of `c` (with two images on either
// side) where the slope (mm per px, maps row-major) is below a tenth of a step per pixel.
struct FocusCurveShape {
  double shoulder = 0.0;  // (f(k-1) + f(k+1) - 2 floor) / (f(k) - floor)
  double cusp = 0.0;      // (P(k+-2) - 1) / (P(k+-1) - 1), P = ((f - floor) / (f(k) - floor))^(-2/3) averaged over +-
  double rise1 = 0.0, rise2 = 0.0;  // P(k+-1) - 1 and P(k+-2) - 1 (their medians apart; PredictedPhaseBiasRms)
  int samples = 0;        // peaks that gave the shape ratio
};
FocusCurveShape MeasureCurveShape(const WindowCurves& c, std::size_t images, double min_quality, const float* slope_x,
                                  const float* slope_y, double step_mm);

// How narrow the stack's focus curves are: 1 for a shoulder below kNarrowShoulderFull, 0 above kNarrowShoulderNone,
// linear between; 0 from fewer than 50 sampled peaks.
double NarrowCurveShare(const FocusCurveShape& shape);

// The share (0 to 1) of the bias the stack's curves show (narrow and V-topped); 0 from fewer than 50 sampled peaks.
double SteepCurvatureBiasShare(const FocusCurveShape& shape);

// Moves each finite height whose window is one of `windows` by -share x kSteepBiasPx x sigma x ramp(slope) x
// laplacian. Where the Laplacian is NaN (near a sharp bend, where its local mean holds the bend's ridge) the height
// is left alone, and `unremoved_mm` (n values, else 0) gets the bias's size from `filled_laplacian` (the curvature
// of the surface around, for the uncertainty). Maps row-major, width x height.
void CorrectSteepCurvatureBias(int width, int height, bool parallel, double share, double step_mm,
                               const std::vector<WindowCurves>& windows, const std::vector<float>& window_px,
                               const float* slope_x, const float* slope_y, const float* laplacian,
                               const float* filled_laplacian, std::vector<double>& z_mm,
                               std::vector<float>& unremoved_mm);

}  // namespace fvm::imaging
