#include "imaging/focus_window_curvature.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <opencv2/imgproc.hpp>

namespace fvm::imaging {
namespace {

// The noise of the Laplacian's local mean, as a share of its departures' rms (the roughness map), in the shrinking
// factor. Calibrated on focusgen.py seeds 11 and 12 (tests/bench/focus_conditions.py): at 0.15-1 the correction's
// noise on a 2 px texture (heights 0.15-0.23 step rms) cost as many cells within 93-97 % as the bottoms gained.
constexpr double kCurvatureNoiseShare = 2.5;

// The variance of normalised 1-D taps about their middle.
double TapVariance(const std::vector<float>& taps) {
  const int half = int(taps.size() / 2);
  double variance = 0.0;
  for (std::size_t j = 0; j < taps.size(); ++j) variance += double(taps[j]) * double((int(j) - half) * (int(j) - half));
  return variance;
}

}  // namespace

double WindowWeightVariancePx2(const WindowCurves& window) {
  const cv::Mat prefilter = cv::getGaussianKernel(2 * kPrefilterHalfWidth + 1, kPrefilterSigmaPx, CV_32F);
  return TapVariance(WindowTaps(window.window, window.gaussian)) +
         TapVariance(std::vector<float>(prefilter.begin<float>(), prefilter.end<float>()));
}

void CorrectWindowCurvature(int width, int height, bool parallel, const std::vector<WindowCurves>& windows,
                            const std::vector<float>& window_px, const float* laplacian, const float* roughness,
                            std::vector<double>& z_mm) {
  std::vector<double> half_variance(windows.size());
  for (std::size_t k = 0; k < windows.size(); ++k) half_variance[k] = 0.5 * WindowWeightVariancePx2(windows[k]);
  ForStripes(height, parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(width); i < std::size_t(r1) * std::size_t(width); ++i) {
      if (!std::isfinite(z_mm[i]) || !std::isfinite(laplacian[i])) continue;
      const double l = laplacian[i], noise = kCurvatureNoiseShare * double(roughness[i]);
      const double clear = l * l / std::max(l * l + noise * noise, 1e-300);
      for (std::size_t k = 0; k < windows.size(); ++k) {
        if (window_px[i] == float(windows[k].window)) z_mm[i] -= half_variance[k] * clear * l;
      }
    }
  });
}

}  // namespace fvm::imaging
