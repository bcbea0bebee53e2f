#include "imaging/subpixel_refinement.h"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "core/dense_decomposition.h"

namespace fvm::imaging::detail {

// Lanczos-4: sinc(x) sinc(x / 4) for |x| < 4.
namespace {

double Lanczos4(double x) {
  if (std::abs(x) < 1e-12) return 1.0;
  if (std::abs(x) >= 4.0) return 0.0;
  const double px = std::numbers::pi * x;
  return 4.0 * std::sin(px) * std::sin(px / 4.0) / (px * px);
}

// The 8 taps of Lanczos-4 interpolation at fraction f in [0, 1): weight j multiplies the sample at j - 3,
// normalised to sum 1 as OpenCV's INTER_LANCZOS4 does. Its pass band is flat to ~0.3 cycles / px, where bicubic
// interpolation already shifts the phase: with bicubic the refined shifts carried a bias of ~0.01-0.04 px that
// repeats at every pair with the same fraction, and so adds up along a row of tiles.
cv::Mat LanczosTaps(double f) {
  cv::Mat taps(1, 8, CV_32F);
  double sum = 0.0;
  for (int j = 0; j < 8; ++j) sum += Lanczos4(f - (j - 3));
  for (int j = 0; j < 8; ++j) taps.at<float>(0, j) = static_cast<float>(Lanczos4(f - (j - 3)) / sum);
  return taps;
}

}  // namespace

// The gradient of an image as Lanczos-4 interpolates it, at the pixels: the derivative of the interpolation in
// the shift, sum_j L'(-k) I(v + k), k = j - 3. Refinement needs this one, not a finite difference: on texture that
// reaches the Nyquist frequency (the roughness of a face in a height map) a Sobel gradient overstates the step
// 2.7-fold and Gauss-Newton oscillates half a pixel off the match.
void InterpolationGradient(const cv::Mat& image, cv::Mat& gx, cv::Mat& gy) {
  static const cv::Mat derivative = [] {
    cv::Mat taps(1, 8, CV_32F);
    constexpr double h = 1e-5;
    for (int j = 0; j < 8; ++j) {
      const double k = j - 3;
      taps.at<float>(0, j) = static_cast<float>((Lanczos4(h - k) - Lanczos4(-h - k)) / (2 * h));
    }
    return taps;
  }();
  // One direction each (a separable filter with an identity pass along the other did the same work twice).
  static const cv::Mat derivative_y = derivative.t();
  cv::filter2D(image, gx, CV_32F, derivative, cv::Point(3, 0), 0.0, cv::BORDER_REFLECT);
  cv::filter2D(image, gy, CV_32F, derivative_y, cv::Point(0, 3), 0.0, cv::BORDER_REFLECT);
}

// A sampled at v + e for every v of `inner` (B's frame). A translation shifts every pixel by the same fraction,
// so the 8 x 8 Lanczos kernel is the product of two 8-tap filters: a separable filter of the window, 16
// multiply-adds a pixel instead of remap's 64. `inner` must keep 4 px of A around it after the shift.
cv::Mat ShiftedCrop(const cv::Mat& a, const Eigen::Vector2d& e, const cv::Rect& inner) {
  const int ix = static_cast<int>(std::floor(e.x())), iy = static_cast<int>(std::floor(e.y()));
  const cv::Rect window(inner.x + ix - 3, inner.y + iy - 3, inner.width + 7, inner.height + 7);
  cv::Mat filtered;
  cv::sepFilter2D(a(window), filtered, CV_32F, LanczosTaps(e.x() - ix), LanczosTaps(e.y() - iy), cv::Point(3, 3),
                  0.0, cv::BORDER_REFLECT);
  return filtered(cv::Rect(3, 3, inner.width, inner.height));
}

// B's interior: `margin` px in from every side, and never into the context around a thin overlap. ShiftedCrop
// reaches 3 px before and 4 px after a pixel, so a margin of 4 + ceil(|e|) keeps a shift by e inside A.
std::optional<cv::Rect> Interior(const Prepared& prepared, int margin) {
  const cv::Mat& b = prepared.value;
  margin = std::max(margin, prepared.pad);
  const cv::Rect inner(margin, margin, b.cols - 2 * margin, b.rows - 2 * margin);
  if (inner.width < kMinOverlapPx || inner.height < kMinOverlapPx) return std::nullopt;
  return inner;
}

// Where a pixel of `inner` counts: B valid there, and A valid wherever its resampling at v + e and the 8-tap
// gradients reach. Empty when both crops are whole.
cv::Mat Usable(const cv::Mat& a_valid, const cv::Mat& b_valid, const Eigen::Vector2d& e, const cv::Rect& inner) {
  if (a_valid.empty() && b_valid.empty()) return {};
  cv::Mat usable = cv::Mat::ones(inner.size(), CV_32F);
  if (!b_valid.empty()) usable = b_valid(inner).clone();
  if (!a_valid.empty()) {
    cv::Mat shifted;
    cv::threshold(ShiftedCrop(a_valid, e, inner), shifted, 0.999, 1.0, cv::THRESH_BINARY);
    usable = usable.mul(shifted);
  }
  cv::erode(usable, usable, cv::Mat::ones(9, 9, CV_8U));
  return usable;
}

Refinement RefineShift(const Prepared& a, const Prepared& b, double tolerance_px, Eigen::Vector2d& e,
                       Eigen::Vector2d* last_step, Eigen::Vector2d* last_estimate) {
  // Up to 4 px from the start: on a lay (marks in one direction) the correlation peak is a ridge, and its top
  // can lie a few pixels along it from the truth.
  constexpr double kWander = 4.0;
  constexpr int kIterations = 30;
  Eigen::Vector2d estimate = e;
  int iteration = 0;
  // The interior leaves room for the current shift and one pixel more; a step beyond it starts over with a
  // wider margin, so that a narrow overlap keeps most of its pixels while the shift stays small.
  while (iteration < kIterations) {
    const double reach = estimate.cwiseAbs().maxCoeff() + 1.0;
    const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(reach)));
    if (!inner) return Refinement::kNoRoom;
    // B's gradient, taken from B's own pixels around the interior.
    cv::Mat gx, gy;
    InterpolationGradient(b.value(*inner), gx, gy);
    const cv::Mat usable = Usable(a.valid, b.valid, estimate, *inner);
    if (!usable.empty()) {
      gx = gx.mul(usable);
      gy = gy.mul(usable);
    }
    const cv::Mat target = b.value(*inner);
    Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
    for (int y = 0; y < gx.rows; ++y) {
      const float* px = gx.ptr<float>(y);
      const float* py = gy.ptr<float>(y);
      for (int x = 0; x < gx.cols; ++x) {
        h(0, 0) += px[x] * px[x];
        h(0, 1) += px[x] * py[x];
        h(1, 1) += py[x] * py[x];
      }
    }
    h(1, 0) = h(0, 1);
    if (!(h.trace() > 0.0)) return Refinement::kNoTexture;
    // Damped by a hundredth of the largest gradient energy: along a direction without texture (machining marks)
    // the energy is the noise's, and undamped steps would follow the noise off the match; with texture the
    // damping only slows each step by 1 %.
    const auto solve = Decompose<Eigen::LDLT<Eigen::Matrix2d>>(h + 0.01 * h.trace() * Eigen::Matrix2d::Identity(),
                                                                "the sub-pixel refinement: the gradient energy");
    for (; iteration < kIterations; ++iteration) {
      const cv::Mat warped = ShiftedCrop(a.value, estimate, *inner);
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      for (int y = 0; y < gx.rows; ++y) {
        const float* px = gx.ptr<float>(y);
        const float* py = gy.ptr<float>(y);
        const float* w = warped.ptr<float>(y);
        const float* t = target.ptr<float>(y);
        for (int x = 0; x < gx.cols; ++x) {
          const double r = w[x] - t[x];
          g(0) += px[x] * r;
          g(1) += py[x] * r;
        }
      }
      // A(v + e) = B(v + d) with d = e - e_true; the step solves B(v + d) ~ B(v) + grad B . d for d.
      const Eigen::Vector2d step = solve.solve(g);
      estimate -= step;
      if (last_step != nullptr) *last_step = step;
      if (last_estimate != nullptr) *last_estimate = estimate;
      if ((estimate - e).norm() > kWander) return Refinement::kWandered;  // off the peak: not the same match
      if (step.norm() < tolerance_px) {
        e = estimate;
        return Refinement::kSettled;
      }
      if (estimate.cwiseAbs().maxCoeff() > reach) {
        ++iteration;
        break;  // beyond the interior's margin: again with a wider one
      }
    }
  }
  // Still moving by more than the tolerance: the estimate is not a minimum, and no precision can be claimed.
  return Refinement::kNotSettled;
}

}  // namespace fvm::imaging::detail
