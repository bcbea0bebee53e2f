#include "imaging/overlap_height_step.h"

#include <cmath>

namespace fvm::imaging {

HeightStep OverlapHeightStep(const TileImage& a, const TileImage& b, const Eigen::Vector2d& offset_px) {
  // Pixel (x, y) of a is pixel (x - ox, y - oy) of b.
  double sum = 0.0, squares = 0.0;  // about the first difference, so that large heights lose no digits
  int n = 0;
  double first = NAN;
  for (Eigen::Index y = 0; y < a.rows(); ++y) {
    const double by = static_cast<double>(y) - offset_px.y();
    const double fy = std::floor(by);
    if (fy < 0.0 || fy + 1.0 >= static_cast<double>(b.rows())) continue;
    for (Eigen::Index x = 0; x < a.cols(); ++x) {
      const double bx = static_cast<double>(x) - offset_px.x();
      const double fx = std::floor(bx);
      if (fx < 0.0 || fx + 1.0 >= static_cast<double>(b.cols())) continue;
      const auto r = static_cast<Eigen::Index>(fy), c = static_cast<Eigen::Index>(fx);
      const double tx = bx - fx, ty = by - fy;
      const double v = (1 - ty) * ((1 - tx) * b(r, c) + tx * b(r, c + 1)) + ty * ((1 - tx) * b(r + 1, c) + tx * b(r + 1, c + 1));
      const double d = static_cast<double>(a(y, x)) - v;
      if (!std::isfinite(d)) continue;  // NaN: an invalid pixel on either side
      if (n == 0) first = d;
      sum += d - first;
      squares += (d - first) * (d - first);
      ++n;
    }
  }
  HeightStep step;
  step.pixels = n;
  if (n == 0) return step;
  const double mean_about_first = sum / n;
  step.mean = first + mean_about_first;
  step.variance = std::max(0.0, squares / n - mean_about_first * mean_about_first) / n;
  return step;
}

}  // namespace fvm::imaging
