#include "imaging/focus_window_curvature.h"

#include <cmath>
#include <cstddef>
#include <opencv2/imgproc.hpp>

namespace fvm::imaging {
namespace {

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
                            const std::vector<float>& window_px, const float* laplacian, std::vector<double>& z_mm) {
  std::vector<double> half_variance(windows.size());
  for (std::size_t k = 0; k < windows.size(); ++k) half_variance[k] = 0.5 * WindowWeightVariancePx2(windows[k]);
  ForStripes(height, parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(width); i < std::size_t(r1) * std::size_t(width); ++i) {
      if (!std::isfinite(z_mm[i]) || !std::isfinite(laplacian[i])) continue;
      for (std::size_t k = 0; k < windows.size(); ++k) {
        if (window_px[i] == float(windows[k].window)) z_mm[i] -= half_variance[k] * double(laplacian[i]);
      }
    }
  });
}

}  // namespace fvm::imaging
