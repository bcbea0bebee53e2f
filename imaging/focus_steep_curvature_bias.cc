#include "imaging/focus_steep_curvature_bias.h"

#include <algorithm>
#include <cmath>

#include "imaging/focus_peak.h"
#include "imaging/focus_window_curvature.h"

namespace fvm::imaging {
namespace {

constexpr std::size_t kShapeEvery = 13;    // a sample of the pixels, prime against the image's width
constexpr double kGentleSlopeSteps = 0.1;  // steps per px: a window's heights span well under a step
constexpr int kMinShapeSamples = 50;

float Median(std::vector<float>& v) {
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// 0 at `none`, 1 at `full`, linear between (either order).
double Ramp(double x, double none, double full) { return std::clamp((x - none) / (full - none), 0.0, 1.0); }

}  // namespace

FocusCurveShape MeasureCurveShape(const WindowCurves& c, std::size_t images, double min_quality, const float* slope_x,
                                  const float* slope_y, double step_mm) {
  std::vector<float> shoulder, cusp, rise1, rise2;
  for (std::size_t i = 0; i < c.best.size(); i += kShapeEvery) {
    const int k = c.index[i];
    if (k < 2 || k + 2 >= int(images)) continue;  // two images on either side, for the shape ratio
    if (std::hypot(slope_x[i], slope_y[i]) > kGentleSlopeSteps * step_mm) continue;
    const float s = PeakShoulder(c, i, images, min_quality);
    if (!std::isfinite(s)) continue;
    shoulder.push_back(s);
    const float floor = c.floor[i], peak = c.best[i] - floor;
    const float l1 = c.left[i] - floor, r1 = c.right[i] - floor, l2 = c.left2[i] - floor, r2 = c.right2[i] - floor;
    if (!(l1 > 0.0f && r1 > 0.0f && l2 > 0.0f && r2 > 0.0f)) continue;
    const auto rise = [&](float f) { return 1.0 / std::cbrt((double(f) / peak) * (double(f) / peak)); };
    const double p1 = 0.5 * (rise(l1) + rise(r1)) - 1.0, p2 = 0.5 * (rise(l2) + rise(r2)) - 1.0;
    if (p1 > 0.0) cusp.push_back(float(p2 / p1)), rise1.push_back(float(p1)), rise2.push_back(float(p2));
  }
  FocusCurveShape out;
  out.samples = int(cusp.size());
  if (!shoulder.empty()) out.shoulder = Median(shoulder);
  if (!cusp.empty()) out.cusp = Median(cusp), out.rise1 = Median(rise1), out.rise2 = Median(rise2);
  return out;
}

double NarrowCurveShare(const FocusCurveShape& shape) {
  if (shape.samples < kMinShapeSamples) return 0.0;
  return Ramp(shape.shoulder, kNarrowShoulderNone, kNarrowShoulderFull);
}

double SteepCurvatureBiasShare(const FocusCurveShape& shape) {
  return NarrowCurveShare(shape) * Ramp(shape.cusp, kCuspNone, kCuspFull);
}

void CorrectSteepCurvatureBias(int width, int height, bool parallel, double share, double step_mm,
                               const std::vector<WindowCurves>& windows, const std::vector<float>& window_px,
                               const float* slope_x, const float* slope_y, const float* laplacian,
                               const float* filled_laplacian, std::vector<double>& z_mm,
                               std::vector<float>& unremoved_mm) {
  unremoved_mm.assign(std::size_t(width) * std::size_t(height), 0.0f);
  if (!(share > 0.0)) return;
  std::vector<double> scale(windows.size());
  for (std::size_t k = 0; k < windows.size(); ++k) {
    scale[k] = share * kSteepBiasPx * std::sqrt(WindowWeightVariancePx2(windows[k]));
  }
  ForStripes(height, parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(width); i < std::size_t(r1) * std::size_t(width); ++i) {
      if (!std::isfinite(z_mm[i])) continue;
      const double slope_steps = std::hypot(slope_x[i], slope_y[i]) / step_mm;
      const double ramp = Ramp(slope_steps, kSteepRampStartSteps, kSteepRampEndSteps);
      if (ramp == 0.0) continue;
      for (std::size_t k = 0; k < windows.size(); ++k) {
        if (window_px[i] != float(windows[k].window)) continue;
        if (std::isfinite(laplacian[i])) {
          z_mm[i] -= scale[k] * ramp * double(laplacian[i]);
        } else if (std::isfinite(filled_laplacian[i])) {
          unremoved_mm[i] = float(scale[k] * ramp * std::abs(double(filled_laplacian[i])));
        }
      }
    }
  });
}

}  // namespace fvm::imaging
