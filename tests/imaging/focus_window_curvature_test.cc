// The window's curvature correction (imaging/focus_window_curvature.h) on a synthetic case whose bias is known: the
// mean of a paraboloid over the window's weights (its taps written from their formula, widened by the pre-filter's).

#include "imaging/focus_window_curvature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace fvm {
namespace {

std::vector<imaging::WindowCurves> AdaptiveWindows() {
  std::vector<imaging::WindowCurves> windows(3);
  for (int k = 0; k < 3; ++k)
    windows[std::size_t(k)].window = 3 + 2 * k + 2 * (k == 2), windows[std::size_t(k)].gaussian = true;
  return windows;  // 3, 5 and 9 px
}

// Normalised 1-D Gaussian taps of sigma `sigma` over 2 half + 1 points.
std::vector<double> Gaussian(double sigma, int half) {
  std::vector<double> t;
  double sum = 0.0;
  for (int j = -half; j <= half; ++j) t.push_back(std::exp(-j * j / (2.0 * sigma * sigma))), sum += t.back();
  for (double& v : t) v /= sum;
  return t;
}

TEST(FocusWindowCurvature, MovesEachHeightByTheWindowsMeanOfAParaboloid) {
  // A paraboloid h = c (x^2 + y^2) / 2 (Laplacian 2c) seen through the 9 px window (Gaussian of sigma 2.7 px to 2.5
  // sigma, rounded: 7 px either side) of a measure pre-filtered by a 5-tap Gaussian of sigma 0.5 px: the window's
  // weighted mean of the heights around a point exceeds the point's height by the weights' variance times c, which
  // the correction takes off.
  const std::vector<double> window = Gaussian(0.3 * 9, 7), prefilter = Gaussian(0.5, 2);
  std::vector<double> weights(window.size() + prefilter.size() - 1, 0.0);  // their convolution, along one axis
  for (std::size_t a = 0; a < window.size(); ++a)
    for (std::size_t b = 0; b < prefilter.size(); ++b) weights[a + b] += window[a] * prefilter[b];
  constexpr double kC = 2e-6;  // mm per px^2: a sphere of 0.5 mm radius in 1 um pixels
  const int half = int(weights.size() / 2);
  double mean = 0.0;  // of c (x^2 + y^2) / 2 over the 2-D weights, the centre at 0
  for (int y = -half; y <= half; ++y)
    for (int x = -half; x <= half; ++x)
      mean += weights[std::size_t(x + half)] * weights[std::size_t(y + half)] * kC * (x * x + y * y) / 2.0;
  const std::vector<imaging::WindowCurves> windows = AdaptiveWindows();
  EXPECT_NEAR(imaging::WindowWeightVariancePx2(windows[2]) * kC, mean, 1e-4 * mean);

  constexpr int kWidth = 4, kHeight = 1;
  const std::vector<float> window_px = {9.0f, 5.0f, 9.0f, 4.0f};
  const std::vector<float> laplacian = {float(2 * kC), float(2 * kC), std::numeric_limits<float>::quiet_NaN(),
                                        float(2 * kC)};
  std::vector<double> z(4, 0.01);
  imaging::CorrectWindowCurvature(kWidth, kHeight, false, windows, window_px, laplacian.data(), z);
  EXPECT_NEAR(z[0], 0.01 - mean, 1e-4 * mean);  // the window's mean of the heights, taken off
  EXPECT_NEAR(z[1], 0.01 - imaging::WindowWeightVariancePx2(windows[1]) * kC, 1e-12);  // the 5 px window's
  EXPECT_LT(imaging::WindowWeightVariancePx2(windows[1]), 0.5 * imaging::WindowWeightVariancePx2(windows[2]));
  EXPECT_EQ(z[2], 0.01);  // no curvature known (near a bend)
  EXPECT_EQ(z[3], 0.01);  // no window of that size
}

}  // namespace
}  // namespace fvm
