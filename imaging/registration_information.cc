#include "imaging/registration_information.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include <opencv2/imgproc.hpp>

#include "core/dense_decomposition.h"
#include "imaging/subpixel_refinement.h"

namespace fvm::imaging::detail {

namespace {

// The quality and information of aligned crops; `area`: pixels per independent noise sample (1 for the crops as
// they are, more once smoothed); `inflation`: the factor by which the errors exceed the noise's part (1, or
// kThinOverlapInflation).
Alignment Measure(const cv::Mat& warped, const cv::Mat& target, const cv::Mat& usable, double area, double inflation) {
  Alignment out;
  // Gradients of both aligned crops.
  cv::Mat bx, by, ax, ay;
  InterpolationGradient(target, bx, by);
  InterpolationGradient(warped, ax, ay);
  // Sums per row in float (a row is at most a few thousand terms), over rows in double. The texture's gradient
  // energy comes from the cross products of A's and B's gradients: the two images' noise is independent, so it
  // adds nothing on average, where the energy of one image's gradients counts its noise too. The energies of A
  // and B alone scale the cross products' spread under pure noise. The quality is the normalised
  // cross-correlation of the values.
  Eigen::Matrix2d cross = Eigen::Matrix2d::Zero(), energy_a = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d energy_b = Eigen::Matrix2d::Zero();
  double n = 0.0, sw = 0.0, st = 0.0, sww = 0.0, stt = 0.0, swt = 0.0;
  for (int y = 0; y < bx.rows; ++y) {
    const float *pbx = bx.ptr<float>(y), *pby = by.ptr<float>(y), *pax = ax.ptr<float>(y), *pay = ay.ptr<float>(y);
    const float* w = warped.ptr<float>(y);
    const float* t = target.ptr<float>(y);
    const float* use = usable.empty() ? nullptr : usable.ptr<float>(y);
    float cxx = 0, cxy = 0, cyx = 0, cyy = 0, axx = 0, axy = 0, ayy = 0, bxx = 0, bxy = 0, byy = 0;
    float count = 0, rw = 0, rt = 0, rww = 0, rtt = 0, rwt = 0;
    for (int x = 0; x < bx.cols; ++x) {
      if (use != nullptr && use[x] == 0.0f) continue;
      cxx += pax[x] * pbx[x], cxy += pax[x] * pby[x], cyx += pay[x] * pbx[x], cyy += pay[x] * pby[x];
      axx += pax[x] * pax[x], axy += pax[x] * pay[x], ayy += pay[x] * pay[x];
      bxx += pbx[x] * pbx[x], bxy += pbx[x] * pby[x], byy += pby[x] * pby[x];
      count += 1, rw += w[x], rt += t[x], rww += w[x] * w[x], rtt += t[x] * t[x], rwt += w[x] * t[x];
    }
    // The cross products symmetrised: A's x gradient against B's y counts as much as the other way round.
    cross += (Eigen::Matrix2d() << cxx, 0.5 * (cxy + cyx), 0.5 * (cxy + cyx), cyy).finished();
    energy_a += (Eigen::Matrix2d() << axx, axy, axy, ayy).finished();
    energy_b += (Eigen::Matrix2d() << bxx, bxy, bxy, byy).finished();
    n += count, sw += rw, st += rt, sww += rww, stt += rtt, swt += rwt;
  }
  if (n < kMinOverlapPx * kMinOverlapPx) return out;
  const double var_w = sww / n - (sw / n) * (sw / n), var_t = stt / n - (st / n) * (st / n);
  const double covariance = swt / n - (sw / n) * (st / n);
  if (!(var_w > 0.0 && var_t > 0.0)) return out;
  out.quality = covariance / std::sqrt(var_w * var_t);
  // The residual's variance: mean of (w - t)^2.
  const double residual = (sww - 2.0 * swt + stt) / n;
  const double variance = std::max(residual, 1e-12 * energy_b.trace() / n);
  const auto directions = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(cross, "a tile pair's registration information");
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d u = directions.eigenvectors().col(k);
    const double texture = directions.eigenvalues()(k);
    // Under noise alone the cross energy along u scatters by sqrt(E_a E_b / n); a direction counts at 8 of
    // those (the filters correlate neighbouring pixels, so n overstates the independent samples a few times).
    const double spread = std::sqrt(u.dot(energy_a * u) * u.dot(energy_b * u) * area / n);
    if (!(texture > 8.0 * spread)) continue;
    // Refinement settles where B's gradient, texture and noise, is orthogonal to the residual; so the shift's
    // variance along u is variance E_b / texture^2, B's gradient energy over the texture's squared (the
    // sandwich of Gauss-Newton with a noisy Jacobian). Below it lies what registration leaves when noise does not
    // dominate (Lanczos resampling of texture near 0.2 cycles / px, remnants of the shading): 0.005 px, the rms
    // error of noise-light synthetic pairs; without it the information overstated 512 px pairs 15-fold.
    const double noise_part = area * variance * u.dot(energy_b * u) / (texture * texture);
    out.information += 1.0 / (inflation * inflation * noise_part + kSystematicPx * kSystematicPx) * u * u.transpose();
  }
  return out;
}

}  // namespace

Alignment MeasureAlignment(const Prepared& a, const Prepared& b, const Eigen::Vector2d& e, double match_sigma) {
  const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(e.cwiseAbs().maxCoeff())));
  if (!inner) return {};
  const cv::Mat target = b.value(*inner);
  const cv::Mat warped = ShiftedCrop(a.value, e, *inner);
  const cv::Mat usable = Usable(a.valid, b.valid, e, *inner);
  const double inflation = b.pad > 0 ? kThinOverlapInflation : 1.0;  // pad: a thin overlap, mirrored out
  Alignment out = Measure(warped, target, usable, 1.0, inflation);
  if (!out.information.isZero() || !(match_sigma > 0.0)) return out;
  // Where the pixel noise drowns the texture's gradients (camera tiles of a printed grid), the same with the noise
  // smoothed away: the gradients of the smoothed crops, their noise counted over the pixels one Gaussian of
  // match_sigma spans (4 pi sigma^2: the smoothed noise's correlation area), so the texture must stand out of fewer,
  // noisier samples.
  cv::Mat smooth_w, smooth_t;
  cv::GaussianBlur(warped, smooth_w, cv::Size(0, 0), match_sigma, match_sigma, cv::BORDER_REFLECT);
  cv::GaussianBlur(target, smooth_t, cv::Size(0, 0), match_sigma, match_sigma, cv::BORDER_REFLECT);
  out.information = Measure(smooth_w, smooth_t, usable, 4.0 * std::numbers::pi * match_sigma * match_sigma, inflation).information;
  return out;
}

}  // namespace fvm::imaging::detail
