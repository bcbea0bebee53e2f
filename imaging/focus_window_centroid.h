#pragma once
// The height a window's focus curve gives on a slope is not the height at the window's centre: the window sums
// the measures of its pixels, each in focus at its own height, weighted by how sharp its texture is, so the peak
// lies at the height under the centroid of those weights (to first order in the spread of heights over the
// window). A random texture puts that centroid off centre by a fraction of a pixel, which on a 24 deg wall is a
// tenth of a micrometre whatever the z step. Knowing the weights and the slope (of the height map), the shift is
// removed. Used by focus_variation.cc.
// The weights: where the stack's focus curves are narrow (NA 0.9 on focusgen.py), each pixel's own peak focus
// measure over the stack (the 3 px window's); where they are wide, the sharpness of the all-in-focus image; in
// between, each shift in proportion (CentroidCorrectionInput::peak_share). The all-in-focus image stands for the
// peak measure only where the light a pixel receives depends on its own defocus alone.
// Where each object point spreads its light by its own defocus (../shared/bench/focusgen.py's scatter model) a
// tilted face's in-focus contour is brighter than its neighbours (the points in focus concentrate their light; a
// PSF whose width changes from point to point does not give a uniform image of a uniform albedo), so the peak
// measure grows with the slope: at NA 0.9 with a 0.8 um floor 1.4, 1.9, 2.3 and 2.9 times a level pixel's at 0.2,
// 0.25, 0.3 and 0.35-0.4 step/px (by a tilted plane rendered apart: 2.4 times at 0.35 step/px whatever the depth
// layers' spacing; 1.0 when each pixel is blurred by its own defocus only). On a curved wall, whose slope grows
// outwards, a window's curve then leans outwards, to higher heights. The all-in-focus image, each pixel taken from
// its own sharpest image, shows that trend distorted (4 times at 0.25 step/px, 5.4-5.8 times from 0.3 on): its
// centroids took 0.007-0.019 step too much off at 0.2-0.3 step/px and, with a 0.8 um floor, 0.04 too little at
// 0.35-0.4 (focusgen.py seeds 11, 12, without the steep-wall term). With the peak measures (and half the steep-wall
// term, focus_steep_curvature_bias.h) NA 0.9 walls read 0.036-0.060 step rms instead of 0.049-0.144 (seeds 11-14).
// Where the curves are wide the peak measure is no better and the all-in-focus image's pixel-level sharpness is
// finer: NA 0.4 walls of ../shared/bench/check focus 0.081 -> 0.084 step with the peak measures, so they are left
// out there. On this project's renderer (no scattered light; focus_accuracy_test.cc) the peak measures lose that
// pixel-level detail too: NA 0.9 walls at 0.5 um steps 0.105 -> 0.112 step.

#include <vector>

#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {

// What the correction needs of a reconstruction (row-major maps of width x height).
struct CentroidCorrectionInput {
  int width = 0, height = 0;
  bool parallel = true;
  const std::vector<float>* texture = nullptr;  // the all-in-focus image, `channels` values per pixel
  int channels = 1;
  const std::vector<WindowCurves>* windows = nullptr;  // the windows' shapes (window, gaussian)
  // The window each height came from (FocusResult::window_px): one of `windows`, or the mean of the first two
  // where their heights were averaged (which then takes half of each one's shift).
  const std::vector<float>* window_px = nullptr;
  const float* slope_x = nullptr;  // height change per pixel (mm) along x and y, from the smoothed map
  const float* slope_y = nullptr;
  // Each pixel's peak focus measure over the stack in the smallest (3 px) window, if there is one: what the pixel
  // adds to a larger window's summed focus curve at its own height, so the weights' first choice. Without it the
  // weights come from the all-in-focus image's sharpness.
  const float* peak_measure = nullptr;
  // How much of the shift the peak measures' weights give (0 to 1), the rest the all-in-focus image's: the share of
  // narrow focus curves in the stack (NarrowCurveShare, focus_steep_curvature_bias.h), 1 at NA 0.9 and 0 at NA
  // 0.3-0.6 on focusgen.py, whose wide curves show no such trend and where the all-in-focus image's pixel-level
  // sharpness is the finer estimate.
  double peak_share = 1.0;
};

// Moves each finite height z_mm[i] by -(slope . centroid offset) of the windows it came from.
void CorrectWindowCentroids(const CentroidCorrectionInput& in, std::vector<double>& z_mm);

}  // namespace fvm::imaging
