#pragma once
// The height a window's focus curve gives on a slope is not the height at the window's centre: the window sums
// the measures of its pixels, each in focus at its own height, weighted by how sharp its texture is, so the peak
// lies at the height under the centroid of those weights (to first order in the spread of heights over the
// window). A random texture puts that centroid off centre by a fraction of a pixel, which on a 24 deg wall is a
// tenth of a micrometre whatever the z step. Knowing the weights (the sharpness of the all-in-focus image) and the
// slope (of the height map), the shift is removed. Used by focus_variation.cc.

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
};

// Moves each finite height z_mm[i] by -(slope . centroid offset) of the windows it came from.
void CorrectWindowCentroids(const CentroidCorrectionInput& in, std::vector<double>& z_mm);

}  // namespace fvm::imaging
