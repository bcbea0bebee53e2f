// The window centroid correction (imaging/focus_window_centroid.h) against the centroids computed here directly:
// each pixel's sharpness (the modified Laplacian of the all-in-focus image smoothed by the focus measure's
// pre-filter, to the power 1.5) weighted by the window's taps written from their formula, their centroid times the
// slope taken off the height.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "imaging/focus_window_centroid.h"

namespace fvm {
namespace {

TEST(FocusWindowCentroid, ShiftsEachHeightByTheSlopeTimesItsWindowsCentroid) {
  constexpr int kWidth = 40, kHeight = 30;
  constexpr double kZ = 0.01, kSlopeX = 4e-4, kSlopeY = -2e-4;  // mm, mm per px
  std::mt19937 random(5);
  std::uniform_real_distribution<float> grey(0.0f, 255.0f);
  std::vector<float> texture(std::size_t(kWidth) * kHeight * 3);  // colour: the weights come from the mean
  for (float& v : texture) v = grey(random);
  std::vector<imaging::WindowCurves> windows(3);
  windows[0].window = 3, windows[0].gaussian = true;
  windows[1].window = 5, windows[1].gaussian = true;
  windows[2].window = 9, windows[2].gaussian = false;
  std::vector<float> window_px(texture.size() / 3);
  for (std::size_t i = 0; i < window_px.size(); ++i) window_px[i] = std::vector<float>{3.0f, 4.0f, 9.0f, 5.0f}[i % 4];
  const std::vector<float> slope_x(window_px.size(), float(kSlopeX)), slope_y(window_px.size(), float(kSlopeY));
  std::vector<double> z(window_px.size(), kZ);
  z[10 * kWidth + 20] = std::numeric_limits<double>::quiet_NaN();

  imaging::CentroidCorrectionInput in;
  in.width = kWidth, in.height = kHeight, in.texture = &texture, in.channels = 3;
  in.windows = &windows, in.window_px = &window_px, in.slope_x = slope_x.data(), in.slope_y = slope_y.data();
  imaging::CorrectWindowCentroids(in, z);

  const auto raw = [&](int x, int y) {
    const auto reflect = [](int i, int n) { return i < 0 ? -i - 1 : i >= n ? 2 * n - i - 1 : i; };
    const float* p = &texture[(std::size_t(reflect(y, kHeight)) * kWidth + std::size_t(reflect(x, kWidth))) * 3];
    return (double(p[0]) + p[1] + p[2]) / 3.0;
  };
  // The focus measure's pre-filter: a Gaussian of sigma kPrefilterSigmaPx over 5 x 5 taps.
  const auto mean = [&](int x, int y) {
    double sum = 0.0, taps = 0.0;
    for (int v = -imaging::kPrefilterHalfWidth; v <= imaging::kPrefilterHalfWidth; ++v) {
      for (int u = -imaging::kPrefilterHalfWidth; u <= imaging::kPrefilterHalfWidth; ++u) {
        const double tap = std::exp(-(u * u + v * v) / (2.0 * imaging::kPrefilterSigmaPx * imaging::kPrefilterSigmaPx));
        sum += tap * raw(x + u, y + v), taps += tap;
      }
    }
    return sum / taps;
  };
  const auto weight = [&](int x, int y) {
    const double c = 2.0 * mean(x, y);
    const double ml = std::abs(c - mean(x - 1, y) - mean(x + 1, y)) + std::abs(c - mean(x, y - 1) - mean(x, y + 1));
    return std::pow(ml, 1.5);
  };
  // The shift of window w (px) at (x, y): Gaussian taps of sigma 0.3 w to 2.5 sigma, or w equal taps.
  const auto shift = [&](int w, bool gaussian, int x, int y) {
    const double sigma = 0.3 * w;
    const int half = gaussian ? int(std::lround(2.5 * sigma)) : w / 2;
    double sum = 0.0, sx = 0.0, sy = 0.0;
    for (int v = -half; v <= half; ++v) {
      for (int u = -half; u <= half; ++u) {
        const double tap = gaussian ? std::exp(-(u * u + v * v) / (2.0 * sigma * sigma)) : 1.0;
        const double a = tap * weight(x + u, y + v);
        sum += a, sx += a * u, sy += a * v;
      }
    }
    return (kSlopeX * sx + kSlopeY * sy) / sum;
  };
  int checked = 0;
  double largest = 0.0;
  for (int y = 6; y < kHeight - 6; ++y) {
    for (int x = 6; x < kWidth - 6; ++x) {
      const std::size_t i = std::size_t(y) * kWidth + std::size_t(x);
      if (!std::isfinite(z[i])) continue;
      const float from = window_px[i];
      const double expected = from == 4.0f ? kZ - 0.5 * (shift(3, true, x, y) + shift(5, true, x, y))
                              : from == 9.0f ? kZ - shift(9, false, x, y)
                                             : kZ - shift(int(from), true, x, y);
      ASSERT_NEAR(z[i], expected, 1e-9) << x << ", " << y << " window " << from;
      largest = std::max(largest, std::abs(z[i] - kZ));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 28 * 18 - 1);
  EXPECT_GT(largest, 1e-4);  // the shifts are real: a fraction of a pixel times 0.45 um per px
  EXPECT_TRUE(std::isnan(z[10 * kWidth + 20]));  // a hole stays a hole
}

}  // namespace
}  // namespace fvm
