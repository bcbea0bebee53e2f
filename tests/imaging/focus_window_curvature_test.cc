// The window's curvature correction (imaging/focus_window_curvature.h) on a synthetic case whose bias is known: the
// mean of a paraboloid over the window's weights (its taps written from their formula, widened by the pre-filter's).

#include "imaging/focus_window_curvature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "imaging/focus_peak.h"
#include "tests/support/focus_windows.h"

namespace fvm {
namespace {

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
  const std::vector<imaging::WindowCurves> windows = imaging::testing::AdaptiveWindows();
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

// The focus curve a window gives on a curved wall, fitted as fvm focus fits it (PowerVertex: the -2/3 power of the
// measure through the best image and two on either side), over many phases of the surface between two images: its
// peak moves with the surface's curvature by about the window's mean of the heights (sigma^2 / 2 x Laplacian, what
// CorrectWindowCurvature takes off), for V-topped focus curves (a cusp, as at NA 0.9 with a 0.8 um floor) as for
// round-topped ones, and not by their weighted median, which a sum of sharp cusps would peak at (the wall's
// curvature along its slope does not move the median). The window's focus curve is the sum of its pixels' curves,
// each in focus at its own height, weighted by the window; the pixel's curve f = (1 + b |u| + c u^2)^(-3/2) (u in
// steps) with b, c those that give the rises one and two images from the peak measured on the flat faces of
// ../shared/bench/focusgen.py at NA 0.9 (0.8 um floor: b 2.77, c 0.59; 0.3 um: b 0.31, c 1.74). A sphere of 400
// steps' radius in pixels of a step (focusgen.py's calotte, 1 um pixels and steps), at slopes of 0.1-0.25 step/px.
TEST(FocusWindowCurvature, ThePeakOfAWallsSummedFocusCurvesMovesByTheWindowsMeanNotItsMedian) {
  const std::vector<double> window = Gaussian(0.3 * 9, 7), prefilter = Gaussian(0.5, 2);
  std::vector<double> weights(window.size() + prefilter.size() - 1, 0.0);
  for (std::size_t a = 0; a < window.size(); ++a)
    for (std::size_t b = 0; b < prefilter.size(); ++b) weights[a + b] += window[a] * prefilter[b];
  const int half = int(weights.size() / 2);
  const double variance = imaging::WindowWeightVariancePx2(imaging::testing::AdaptiveWindows()[2]);
  constexpr double kRadius = 400.0;  // steps (and px)
  constexpr int kImages = 17, kPhases = 32;
  std::vector<double> images(kImages);
  for (int k = 0; k < kImages; ++k) images[std::size_t(k)] = k - kImages / 2;
  struct Shape {
    double b, c;
  };
  for (const Shape shape : {Shape{2.77, 0.59}, Shape{0.31, 1.74}}) {
    const auto curve = [&](double u) {
      const double p = 1.0 + shape.b * std::abs(u) + shape.c * u * u;
      return 1.0 / (p * std::sqrt(p));
    };
    for (const double slope : {0.1, 0.2, 0.25}) {
      SCOPED_TRACE("b " + std::to_string(shape.b) + ", slope " + std::to_string(slope) + " step/px");
      const double depth = kRadius / std::sqrt(1.0 + slope * slope), along = slope * depth;
      // The window's heights (steps) about its centre's, on the sphere and on the plane of the same slope.
      std::vector<double> sphere, plane, weight;
      for (int y = -half; y <= half; ++y)
        for (int x = -half; x <= half; ++x) {
          const double r2 = (along + x) * (along + x) + double(y * y);
          sphere.push_back(depth - std::sqrt(kRadius * kRadius - r2));
          plane.push_back(slope * x);
          weight.push_back(weights[std::size_t(x + half)] * weights[std::size_t(y + half)]);
        }
      // The fitted peak's mean error over the phases of the centre's height between two images.
      const auto peak_error = [&](const std::vector<double>& heights) {
        double error = 0.0;
        for (int j = 0; j < kPhases; ++j) {
          const double phase = (j + 0.5) / kPhases - 0.5;
          std::vector<double> measure(kImages, 0.0);
          for (int k = 0; k < kImages; ++k)
            for (std::size_t i = 0; i < heights.size(); ++i)
              measure[std::size_t(k)] += weight[i] * curve(images[std::size_t(k)] - phase - heights[i]);
          const int best = int(std::max_element(measure.begin(), measure.end()) - measure.begin());
          const std::array<double, 5> f = {measure[std::size_t(best - 2)], measure[std::size_t(best - 1)],
                                           measure[std::size_t(best)], measure[std::size_t(best + 1)],
                                           measure[std::size_t(best + 2)]};
          error += imaging::PowerVertex(images, best, f, 0.0, -2.0 / 3.0) - phase;
        }
        return error / kPhases;
      };
      const double shift = peak_error(sphere) - peak_error(plane);
      // The window's mean and weighted median of the sphere's heights.
      double mean = 0.0;
      for (std::size_t i = 0; i < sphere.size(); ++i) mean += weight[i] * sphere[i];
      std::vector<std::size_t> order(sphere.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sphere[a] < sphere[b]; });
      double below = 0.0, median = 0.0;
      for (const std::size_t i : order) {
        if (below + weight[i] >= 0.5) {
          median = sphere[i];
          break;
        }
        below += weight[i];
      }
      const double laplacian = (2.0 + slope * slope) / depth;  // across (1 / depth) and along (its (1 + slope^2))
      EXPECT_NEAR(mean, 0.5 * variance * laplacian, 0.02 * mean);
      EXPECT_LT(median, 0.5 * mean);
      // 0.99 of the mean at 0.1 step/px, 0.85 at 0.2 and 0.77-0.80 at 0.25 (the round top the lower): a shortfall
      // that grows with the slope, about the same for both shapes (the fit's five images see the summed curve over
      // a step's scale, not its cusp).
      EXPECT_GT(shift, 0.65 * mean);
      EXPECT_LT(shift, 1.05 * mean);
      EXPECT_LT(std::abs(shift - mean), 0.45 * (mean - median));
    }
  }
}

}  // namespace
}  // namespace fvm
