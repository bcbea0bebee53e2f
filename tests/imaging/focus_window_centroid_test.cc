// The window centroid correction (imaging/focus_window_centroid.h) against the centroids computed here directly:
// each pixel's sharpness (the modified Laplacian of the all-in-focus image smoothed by the focus measure's
// pre-filter, to the power 1.5) weighted by the window's taps written from their formula, their centroid times the
// slope taken off the height.

#include <gtest/gtest.h>

#include <algorithm>
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

// With each pixel's peak focus measure given (the 3 px window's), the weights are that measure to the power 1.5 and
// the all-in-focus image is not read: on a plane of one slope whose peak measure grows along x (as a tilted face's
// does under scattered light), the shift of a 9 px Gaussian window is its taps times measure^1.5 summed here
// directly, the same at every pixel away from the edges; a pixel without a peak (NaN) weighs nothing.
TEST(FocusWindowCentroid, WeighsByThePeakMeasureWhereOneIsGiven) {
  constexpr int kWidth = 36, kHeight = 24;
  constexpr double kZ = 0.02, kSlopeX = 3e-4, kSlopeY = 1e-4, kGrowth = 0.12;  // mm, mm per px, per px
  std::vector<float> texture(std::size_t(kWidth) * kHeight, std::numeric_limits<float>::quiet_NaN());
  std::vector<float> peak(texture.size());
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) peak[std::size_t(y) * kWidth + std::size_t(x)] = float(std::exp(kGrowth * x));
  }
  const int hole_x = 20, hole_y = 12;  // no peak here: its neighbours' windows lose its weight
  peak[std::size_t(hole_y) * kWidth + hole_x] = std::numeric_limits<float>::quiet_NaN();
  std::vector<imaging::WindowCurves> windows(3);
  windows[0].window = 3, windows[1].window = 5, windows[2].window = 9;
  for (auto& w : windows) w.gaussian = true;
  const std::vector<float> window_px(texture.size(), 9.0f);
  const std::vector<float> slope_x(texture.size(), float(kSlopeX)), slope_y(texture.size(), float(kSlopeY));
  std::vector<double> z(texture.size(), kZ);
  imaging::CentroidCorrectionInput in;
  in.width = kWidth, in.height = kHeight, in.texture = &texture, in.channels = 1;
  in.windows = &windows, in.window_px = &window_px, in.slope_x = slope_x.data(), in.slope_y = slope_y.data();
  in.peak_measure = peak.data();
  imaging::CorrectWindowCentroids(in, z);

  const auto expected = [&](int x, int y) {  // Gaussian taps of sigma 2.7 px to 7 px, weights peak^1.5
    double sum = 0.0, sx = 0.0, sy = 0.0;
    for (int v = -7; v <= 7; ++v) {
      for (int u = -7; u <= 7; ++u) {
        const bool hole = x + u == hole_x && y + v == hole_y;
        const double taps = std::exp(-(u * u + v * v) / (2.0 * 2.7 * 2.7));
        const double a = hole ? 0.0 : taps * std::exp(1.5 * kGrowth * (x + u));
        sum += a, sx += a * u, sy += a * v;
      }
    }
    return kZ - (kSlopeX * sx + kSlopeY * sy) / sum;
  };
  for (int y = 7; y < kHeight - 7; ++y) {
    for (int x = 7; x < kWidth - 7; ++x) {
      ASSERT_NEAR(z[std::size_t(y) * kWidth + std::size_t(x)], expected(x, y), 1e-9) << x << ", " << y;
    }
  }
  // Away from the hole every shift is the same: the measure's growth times the window's variance, 0.12 x 1.5 x
  // 2.7^2 = 1.3 px along x (a little less: the taps end at 7 px), none along y.
  const double far = z[std::size_t(hole_y) * kWidth + 8] - kZ;
  EXPECT_NEAR(far, -kSlopeX * 1.5 * kGrowth * 2.7 * 2.7, 0.1 * kSlopeX);
  EXPECT_GT(std::abs(z[std::size_t(hole_y) * kWidth + hole_x] - z[std::size_t(hole_y) * kWidth + 8]), 1e-8);
}

// The share of the peak measures' weights mixes the two shifts linearly: at a share of 0.3 each height moves by 0.7
// of the all-in-focus image's shift plus 0.3 of the peak measures' (the shift is linear in the weights' centroid,
// computed per weighting); without a peak measure the share is ignored. The two shifts differ (a test that could
// not fail otherwise).
TEST(FocusWindowCentroid, MixesTheTwoWeightsShiftsByThePeakShare) {
  constexpr int kWidth = 32, kHeight = 28;
  constexpr double kZ = 0.015, kSlopeX = 2e-4, kSlopeY = 3e-4;  // mm, mm per px
  std::mt19937 random(17);
  std::uniform_real_distribution<float> grey(0.0f, 1.0f);
  std::vector<float> texture(std::size_t(kWidth) * kHeight), peak(texture.size());
  for (float& v : texture) v = grey(random);
  for (float& v : peak) v = 1.0f + 4.0f * grey(random);
  std::vector<imaging::WindowCurves> windows(3);
  windows[0].window = 3, windows[1].window = 5, windows[2].window = 9;
  for (auto& w : windows) w.gaussian = true;
  std::vector<float> window_px(texture.size());
  for (std::size_t i = 0; i < window_px.size(); ++i) window_px[i] = i % 3 == 0 ? 5.0f : (i % 3 == 1 ? 9.0f : 7.0f);
  const std::vector<float> slope_x(texture.size(), float(kSlopeX)), slope_y(texture.size(), float(kSlopeY));
  const auto corrected = [&](const float* peak_measure, double share) {
    std::vector<double> z(texture.size(), kZ);
    imaging::CentroidCorrectionInput in;
    in.width = kWidth, in.height = kHeight, in.texture = &texture, in.channels = 1;
    in.windows = &windows, in.window_px = &window_px, in.slope_x = slope_x.data(), in.slope_y = slope_y.data();
    in.peak_measure = peak_measure, in.peak_share = share;
    imaging::CorrectWindowCentroids(in, z);
    return z;
  };
  const std::vector<double> sharpness = corrected(peak.data(), 0.0), by_peak = corrected(peak.data(), 1.0);
  const std::vector<double> mixed = corrected(peak.data(), 0.3), without = corrected(nullptr, 1.0);
  double differ = 0.0;
  for (std::size_t i = 0; i < mixed.size(); ++i) {
    ASSERT_NEAR(mixed[i] - kZ, 0.7 * (sharpness[i] - kZ) + 0.3 * (by_peak[i] - kZ), 1e-12) << i;
    ASSERT_EQ(without[i], sharpness[i]) << i;
    differ = std::max(differ, std::abs(by_peak[i] - sharpness[i]));
  }
  EXPECT_GT(differ, 0.1 * kSlopeX);  // the two weights put the centroids a tenth of a pixel or more apart somewhere
}

}  // namespace
}  // namespace fvm
