// The steep-wall correction (imaging/focus_steep_curvature_bias.h): the typical focus curve's shape told from
// curves of a known form (a smooth waist, a cone from a floor, a wide cone), and the move of the heights it makes.

#include "imaging/focus_steep_curvature_bias.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "imaging/focus_window_curvature.h"
#include "tests/support/focus_windows.h"

namespace fvm {
namespace {

// Window curves of n pixels, each with its peak at image k of a stack and the measures f(k + j) = curve(j - offset).
template <typename Curve>
imaging::WindowCurves Curves(std::size_t n, int k, double offset, const Curve& curve) {
  imaging::WindowCurves c;
  c.window = 9, c.gaussian = true;
  c.Reset(9, true, n);
  for (std::size_t i = 0; i < n; ++i) {
    const double o = offset * double(int(i % 7) - 3) / 3.0;  // the peak's place between images, spread
    c.index[i] = k;
    c.best[i] = float(curve(-o)), c.left[i] = float(curve(-1 - o)), c.right[i] = float(curve(1 - o));
    c.left2[i] = float(curve(-2 - o)), c.right2[i] = float(curve(2 - o));
    c.floor[i] = 0.0f;
    c.sum[i] = c.best[i];  // peak over mean: the number of images
  }
  return c;
}

TEST(FocusSteepCurvatureBias, TellsASharpToppedNarrowCurveFromASmoothWaist) {
  constexpr std::size_t kN = 2000, kImages = 40;
  const std::vector<float> flat(kN, 0.0f);
  constexpr double kStep = 0.001;
  // The modified Laplacian falls as the blur's sigma^-3 (focus_peak.cc). A waist of sigma^2 = s0^2 + (k dz)^2
  // (in steps: s0 = 0.6, k = 1): the transformed measure is a parabola, its rise two images out four times that one
  // image out; a cone from its floor, sigma = s0 + k |dz|: a V-topped rise, about 2.5 times.
  const auto waist = [](double dz) { return std::pow(0.36 + dz * dz, -1.5); };
  const auto cone = [](double dz) { return std::pow(0.6 + std::abs(dz), -3.0); };
  const imaging::FocusCurveShape round =
      imaging::MeasureCurveShape(Curves(kN, 10, 0.0, waist), kImages, 0.0, flat.data(), flat.data(), kStep);
  const imaging::FocusCurveShape sharp =
      imaging::MeasureCurveShape(Curves(kN, 10, 0.0, cone), kImages, 0.0, flat.data(), flat.data(), kStep);
  EXPECT_NEAR(round.cusp, 4.0, 1e-3);
  EXPECT_NEAR(sharp.cusp, (std::pow(2.6 / 0.6, 2.0) - 1.0) / (std::pow(1.6 / 0.6, 2.0) - 1.0), 1e-3);
  EXPECT_LT(sharp.cusp, imaging::kCuspFull);
  EXPECT_LT(sharp.shoulder, imaging::kNarrowShoulderFull);
  EXPECT_DOUBLE_EQ(imaging::SteepCurvatureBiasShare(sharp), 1.0);
  EXPECT_DOUBLE_EQ(imaging::SteepCurvatureBiasShare(round), 0.0);
  // The same cone 33 times wider (a small aperture): the shoulder is wide, nothing to remove.
  const auto wide = [](double dz) { return std::pow(20.0 + std::abs(dz), -3.0); };
  const imaging::FocusCurveShape low_na =
      imaging::MeasureCurveShape(Curves(kN, 10, 0.0, wide), kImages, 0.0, flat.data(), flat.data(), kStep);
  EXPECT_GT(low_na.shoulder, imaging::kNarrowShoulderNone);
  EXPECT_DOUBLE_EQ(imaging::SteepCurvatureBiasShare(low_na), 0.0);
  // Peaks at the stack's ends and on steep parts are not sampled.
  const std::vector<float> steep(kN, float(0.5 * kStep));
  EXPECT_EQ(
      imaging::MeasureCurveShape(Curves(kN, 10, 0.0, cone), kImages, 0.0, steep.data(), flat.data(), kStep).samples, 0);
  EXPECT_EQ(imaging::MeasureCurveShape(Curves(kN, 1, 0.0, cone), kImages, 0.0, flat.data(), flat.data(), kStep).samples,
            0);
  EXPECT_DOUBLE_EQ(imaging::SteepCurvatureBiasShare({}), 0.0);
}

TEST(FocusSteepCurvatureBias, TakesTheBiasOffSteepCurvedWallsOnly) {
  constexpr double kStep = 0.001, kLaplacian = 5e-6;  // mm per px^2
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const std::vector<imaging::WindowCurves> windows = imaging::testing::AdaptiveWindows();
  const std::vector<float> window_px(5, 9.0f), gy(5, 0.0f);
  const double middle = 0.5 * (imaging::kSteepRampStartSteps + imaging::kSteepRampEndSteps);  // of the ramp
  const std::vector<float> gx = {0.0f, float(middle * kStep), float(0.4 * kStep), float(0.4 * kStep), float(0.4 * kStep)};
  const std::vector<float> laplacian = {float(kLaplacian), float(kLaplacian), float(kLaplacian), kNaN, kNaN};
  const std::vector<float> filled = {float(kLaplacian), float(kLaplacian), float(kLaplacian), float(-kLaplacian), kNaN};
  std::vector<double> z(5, 0.02);
  std::vector<float> unremoved;
  imaging::CorrectSteepCurvatureBias(5, 1, false, 0.5, kStep, windows, window_px, gx.data(), gy.data(),
                                     laplacian.data(), filled.data(), z, unremoved);
  const double full =
      0.5 * imaging::kSteepBiasPx * std::sqrt(imaging::WindowWeightVariancePx2(windows[2])) * kLaplacian;
  EXPECT_EQ(z[0], 0.02);                              // a gentle slope
  EXPECT_NEAR(z[1], 0.02 - 0.5 * full, 1e-6 * full);  // half way up the ramp (the slope in float)
  EXPECT_NEAR(z[2], 0.02 - full, 1e-6 * full);
  EXPECT_EQ(z[3], 0.02);  // no curvature known here: the bias's size from the curvature around goes to u_z
  EXPECT_EQ(z[4], 0.02);
  ASSERT_EQ(unremoved.size(), 5u);
  EXPECT_EQ(unremoved[0], 0.0f);
  EXPECT_EQ(unremoved[2], 0.0f);
  EXPECT_NEAR(unremoved[3], full, 1e-6 * full);
  EXPECT_EQ(unremoved[4], 0.0f);
  std::vector<double> none(5, 0.02);
  imaging::CorrectSteepCurvatureBias(5, 1, false, 0.0, kStep, windows, window_px, gx.data(), gy.data(),
                                     laplacian.data(), filled.data(), none, unremoved);
  EXPECT_EQ(none, std::vector<double>(5, 0.02));
  EXPECT_EQ(unremoved, std::vector<float>(5, 0.0f));
}

}  // namespace
}  // namespace fvm
