#include "imaging/focus_peak.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fvm::imaging {
namespace {

// Neighbours less than this share of the peak above the floor: a narrow curve (see FitPeak).
constexpr double kNarrowShare = 0.05;
// A stack whose typical focus curve has its best image's two neighbours summing to less than this share of the
// peak above the floor samples the curve more coarsely than its width (steps longer than the depth of field):
// every peak is then fitted as a narrow one (see CoarselySampled).
constexpr double kCoarseShoulder = 0.6;
// The noise on each measure: its floor (the measure far out of focus) times kNoiseScale over the window's side
// (the sum of window^2 pixels of independent noise), at kNoiseShare (focus_variation.cc's uncertainty model);
// the floor taken off the measures before the power transform, as a share of the smallest measure.
constexpr double kNoiseScale = 0.128;
constexpr double kNoiseShare = 1.15;  // the propagated noise's weight (its linearisation misses a little)
// The power fit's: the errors the noise makes are shared by a window's pixels, so the heights' roughness and the
// fits' disagreement (`model`, focus_variation.cc) show most of them too, and the terms add in quadrature.
constexpr double kPowerNoiseShare = 0.46;
constexpr double kFloorShare = 1.0;
// A narrow curve's 3-point log fit errs between images by a share of the step which no noise shows.
constexpr double kNarrowStepFraction = 0.11;

}  // namespace

// The exponent p of the measure's fall with the blur sigma s (measure ~ s^-p) for a random texture: the
// modified Laplacian is a sum of absolute second derivatives (s^-3 in 2-D), the gradient energy a squared first
// derivative (s^-4), the variance of a texture smoothed by s falls as s^-2.
double BlurExponent(FocusMeasure measure) {
  switch (measure) {
    case FocusMeasure::kModifiedLaplacian:
      return 3.0;
    case FocusMeasure::kTenengrad:
      return 4.0;
    case FocusMeasure::kVariance:
      return 2.0;
  }
  return 2.0;
}

namespace {

// x^power for x > 0, by the cheaper root for the focus measures' transforms (-2/3 for the modified Laplacian,
// -1/2 for the gradient energy, -1 for the variance): std::pow took most of the peak fit's time.
double Power(double x, double power) {
  if (power == -2.0 / 3.0) return 1.0 / std::cbrt(x * x);
  if (power == -0.5) return 1.0 / std::sqrt(x);
  if (power == -1.0) return 1.0 / x;
  return std::pow(x, power);
}

// The Birge ratio of the fit: sqrt(chi^2 / dof) of the points about the parabola, their noise being `sigma` on
// the measure (inverse variances over `weight_scale`^2), times kMisfitScale, at least 1; 1 without a spare point
// (3 points fit any parabola). A focus curve that departs from the model (the renderer's and the optics' blur
// are no exact power law) shows it here, and the vertex's noise is scaled by it: where the misfit dominates, the
// noise estimate is the points' own scatter, whatever sigma. kMisfitScale is calibrated with the constants of
// focus_variation.cc on the stacks of focus_accuracy_test.cc: 0.35, so that only a misfit of about three times
// the noise counts (the flat top of the focus curve misfits all five points of a wide curve, mostly
// symmetrically, which hardly moves the vertex).
constexpr double kMisfitScale = 0.35;
double MisfitRatio(const double* s, const double* t, double det, const double* weight, const double* u,
                   const double* p, const double* inverse_variance, double weight_scale) {
  int points = 0;
  for (int j = 0; j < 5; ++j) points += weight[j] > 0.0;
  if (points <= 3 || !std::isfinite(weight_scale)) return 1.0;
  const double det0 = t[0] * (s[2] * s[4] - s[3] * s[3]) - s[1] * (t[1] * s[4] - s[3] * t[2]) +
                      s[2] * (t[1] * s[3] - s[2] * t[2]);
  const double det1 = s[0] * (t[1] * s[4] - s[3] * t[2]) - t[0] * (s[1] * s[4] - s[3] * s[2]) +
                      s[2] * (s[1] * t[2] - t[1] * s[2]);
  const double det2 = s[0] * (s[2] * t[2] - t[1] * s[3]) - s[1] * (s[1] * t[2] - t[1] * s[2]) +
                      t[0] * (s[1] * s[3] - s[2] * s[2]);
  double chi2 = 0.0;
  for (int j = 0; j < 5; ++j) {
    if (!(weight[j] > 0.0)) continue;
    const double r = p[j] - (det0 + det1 * u[j] + det2 * u[j] * u[j]) / det;
    chi2 += inverse_variance[j] * r * r;
  }
  chi2 *= weight_scale * weight_scale;
  return std::max(1.0, kMisfitScale * std::sqrt(chi2 / double(points - 3)));
}

}  // namespace

// The vertex of the parabola through (z0, f0), (z1, f1), (z2, f2), with f1 the largest; z1 when the three are
// not a maximum (flat or collinear). Stays between z0 and z2.
double Vertex(double z0, double z1, double z2, double f0, double f1, double f2) {
  const double a = (z1 - z0) * (f1 - f2), b = (z1 - z2) * (f1 - f0);
  const double denominator = a - b;
  if (!(std::abs(denominator) > 0.0)) return z1;
  const double z = z1 - 0.5 * ((z1 - z0) * a - (z1 - z2) * b) / denominator;
  if (!std::isfinite(z)) return z1;
  return std::clamp(z, std::min(z0, z2), std::max(z0, z2));
}

// The vertex of the parabola fitted by weighted least squares through the transformed measures P = f^power
// (power < 0: P is smallest at the peak) of the best image k and up to two images on either side. Each point is
// weighted by (f / f_best)^2, so that the points near the floor of a narrow focus curve, where the transform
// blows the noise up, barely count, while a wide curve (small aperture, fine steps) is fitted by its five points.
// Not by 1 / var(P) ~ f^(2 - 2 power) (f^3.3 for the modified Laplacian): near its top the focus curve is
// flatter than the power law (a blur below a pixel hardly changes the image), and weights that lean on the top
// points pull the vertex towards or away from the best image by up to a tenth of a step (measured on the
// stacks of focus_accuracy_test.cc: 0.09 step rms on the flat at 1 um steps and NA 0.7, 0.05 with these
// weights). Stays between the best image's neighbours; z (mm) of the images, NaN measures (beyond the stack)
// left out.
//
// With `u_noise`, also the vertex's standard deviation when each measure carries noise `sigma`: the change of
// the vertex when one measure moves by sigma, linearised in the transform (dP = power P sigma / f), summed in
// quadrature over the points.
double PowerVertex(const std::vector<double>& z, int k, std::array<double, 5> f, double floor, double power,
                   double sigma, double* u_noise) {
  for (double& v : f) v -= floor;
  const double z1 = z[std::size_t(k)];
  if (u_noise) *u_noise = 0.0;
  if (!(f[2] > 0.0)) return z1;
  const double scale = std::abs(z[std::size_t(k) + 1] - z[std::size_t(k) - 1]) / 2.0;
  const double lo = std::min(z[std::size_t(k) - 1], z[std::size_t(k) + 1]);
  const double hi = std::max(z[std::size_t(k) - 1], z[std::size_t(k) + 1]);
  // Normal equations of the weighted fit P = c0 + c1 u + c2 u^2: sums of w u^n (n = 0..4) and w P u^n (0..2).
  double s[5] = {}, t[3] = {};
  double weight[5] = {}, u[5] = {}, p[5] = {}, inverse_variance[5] = {};
  for (int j = 0; j < 5; ++j) {
    const int image = k + j - 2;
    if (!(f[std::size_t(j)] > 0.0) || image < 0 || image >= int(z.size())) continue;
    const double ratio = f[std::size_t(j)] / f[2];
    p[j] = Power(ratio, power);
    weight[j] = ratio * ratio;
    inverse_variance[j] = weight[j] / (p[j] * p[j]);  // ratio^(2 - 2 power), over weight_scale^2 (below)
    u[j] = (z[std::size_t(image)] - z1) / scale;
    double un = weight[j];
    for (int n = 0; n < 5; ++n, un *= u[j]) {
      s[n] += un;
      if (n < 3) t[n] += un * p[j];
    }
  }
  // Cramer's rule on [[s0 s1 s2] [s1 s2 s3] [s2 s3 s4]] (c0 c1 c2) = (t0 t1 t2): the vertex -c1 / (2 c2) needs
  // only the determinants of the matrix with its second and third columns replaced, and their signs the main one.
  const double det = s[0] * (s[2] * s[4] - s[3] * s[3]) - s[1] * (s[1] * s[4] - s[3] * s[2]) +
                     s[2] * (s[1] * s[3] - s[2] * s[2]);
  if (!(std::abs(det) > 0.0)) return z1;
  // det1 and det2 (the determinants with the second and third column replaced by t) are linear in t: their
  // cofactors, so that the vertex for a moved t (the noise below) costs two dot products.
  const double a1[3] = {s[3] * s[2] - s[1] * s[4], s[0] * s[4] - s[2] * s[2], s[1] * s[2] - s[0] * s[3]};
  const double a2[3] = {s[1] * s[3] - s[2] * s[2], s[1] * s[2] - s[0] * s[3], s[0] * s[2] - s[1] * s[1]};
  const auto solve = [&](double det1, double det2, double& vertex) {
    if (!(det2 / det > 0.0)) return false;  // no minimum of P: no peak
    const double v = std::clamp(-det1 / (2.0 * det2), -1.0, 1.0);
    if (!std::isfinite(v)) return false;
    vertex = std::clamp(z1 + v * scale, lo, hi);
    return true;
  };
  const double det1 = a1[0] * t[0] + a1[1] * t[1] + a1[2] * t[2];
  const double det2 = a2[0] * t[0] + a2[1] * t[1] + a2[2] * t[2];
  double z0 = z1;
  if (!solve(det1, det2, z0)) return z1;
  // The sum over the fitted images of the vertex's squared move when image j's t moves by w dP (1, u, u^2), dP its
  // measure's move (`move_of_measure(j)`, as a share of power P).
  const auto vertex_variance = [&](const auto& move_of_measure) {
    double variance = 0.0;
    for (int j = 0; j < 5; ++j) {
      if (!(weight[j] > 0.0)) continue;
      const double d0 = weight[j] * power * p[j] * move_of_measure(j);
      const double dt[3] = {d0, d0 * u[j], d0 * u[j] * u[j]};
      double vertex = z1;
      if (!solve(det1 + a1[0] * dt[0] + a1[1] * dt[1] + a1[2] * dt[2],
                 det2 + a2[0] * dt[0] + a2[1] * dt[1] + a2[2] * dt[2], vertex)) {
        vertex = z1;
      }
      variance += (vertex - z0) * (vertex - z0);
    }
    return variance;
  };
  if (u_noise) {
    // The measure moves by sigma.
    const double variance = vertex_variance([&](int j) { return sigma / f[std::size_t(j)]; });
    *u_noise = std::sqrt(variance) * MisfitRatio(s, t, det, weight, u, p, inverse_variance, f[2] / (power * sigma));
  }
  return z0;
}


Peak FitPeak(const WindowCurves& c, std::size_t i, const std::vector<double>& z,
             const FocusVariationOptions& options, bool coarse) {
  const int n = static_cast<int>(z.size());
  Peak out;
  const float mean = c.sum[i] / static_cast<float>(n);
  out.quality = mean > 0.0f ? c.best[i] / mean : 0.0f;
  const int k = c.index[i];
  if (!(out.quality >= static_cast<float>(options.min_quality))) return out;
  // A peak at either end may lie beyond the stack: its height is unknown, not the end's z; unless the user asks
  // for the end's z (a stack that stops at the surface's nearest or farthest part), with a whole step of
  // uncertainty.
  if (k == 0 || k == n - 1) {
    if (options.keep_end_peaks) out.z = z[std::size_t(k)], out.u = std::abs(z[1] - z[0]);
    return out;
  }
  const std::array<double, 5> f = {c.left2[i], c.left[i], c.best[i], c.right[i], c.right2[i]};
  const double sigma = kNoiseScale / double(c.window) * std::max(double(c.floor[i]), 0.0);
  const double floor_i = kFloorShare * c.floor[i];
  // A curve so narrow that the best image's neighbours lie on its floor (steps coarse against the depth of
  // field) leaves the power transform nothing but the floor's noise there: the log-Gaussian 3-point fit
  // through the raw measures does better.
  const bool narrow = coarse || std::min(f[1], f[3]) - floor_i < kNarrowShare * (f[2] - floor_i);
  if (options.peak_fit == PeakFit::kPower && !narrow) {
    const double power = -2.0 / BlurExponent(options.measure);  // measure^(-2/p) ~ s^2
    out.z = PowerVertex(z, k, f, floor_i, power, sigma, &out.u);
    out.u *= kPowerNoiseShare;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    out.model = std::abs(PowerVertex(z, k, {nan, f[1], f[2], f[3], nan}, floor_i, power) - out.z);
    return out;
  }
  // The other fits through the best image and its neighbours; the noise by moving each measure in turn.
  const auto vertex = [&](const std::array<double, 5>& g) {
    std::array<double, 3> h = {g[1], g[2], g[3]};
    if ((narrow || options.peak_fit == PeakFit::kGaussian) && h[0] > 0.0 && h[2] > 0.0) {
      for (double& v : h) v = std::log(v);
    }
    return Vertex(z[std::size_t(k) - 1], z[std::size_t(k)], z[std::size_t(k) + 1], h[0], h[1], h[2]);
  };
  out.z = vertex(f);
  double variance = 0.0;
  for (std::size_t j = 1; j < 4; ++j) {
    if (!std::isfinite(f[j])) continue;
    std::array<double, 5> g = f;
    g[j] += sigma;
    const double d = vertex(g) - out.z;
    variance += d * d;
  }

  // A narrow curve's 3-point fit errs by up to half a step between images, which no noise shows.
  out.u = kNoiseShare * std::sqrt(variance);
  if (narrow) out.u = std::hypot(out.u, kNarrowStepFraction * std::abs(z[std::size_t(k) + 1] - z[std::size_t(k)]));
  return out;
}

// Whether the stack samples its focus curves more coarsely than their width (z steps longer than the depth of
// field): then the best image's neighbours lie on the curve's tails, where it departs from the power law most,
// and the 3-point log fit does better than the power fit for every pixel, not only for the narrowest curves.
// Judged on the median over a sample of the valid pixels of the neighbours' share of the peak above the floor
// (on the stacks of focus_accuracy_test.cc: 0.36 at 2 um steps and NA 0.9, where the log fit gives 0.14 step rms
// and the power fit 0.21; 0.86 at 1 um and NA 0.9, 1.4-1.8 at finer sampling, where the power fit is the better).
float PeakShoulder(const WindowCurves& c, std::size_t i, std::size_t images, double min_quality) {
  const int k = c.index[i];
  const float peak = c.best[i] - c.floor[i];
  const bool valid = c.best[i] * float(images) >= float(min_quality) * c.sum[i];  // peak over mean
  if (k == 0 || k + 1 >= int(images) || !(peak > 0.0f) || !valid) return std::numeric_limits<float>::quiet_NaN();
  return (c.left[i] + c.right[i] - 2.0f * c.floor[i]) / peak;
}

bool CoarselySampled(const WindowCurves& c, std::size_t images, double min_quality) {
  constexpr std::size_t kEvery = 61;  // a sample of the pixels, prime against the image's width
  std::vector<float> shoulder;
  for (std::size_t i = 0; i < c.best.size(); i += kEvery) {
    const float s = PeakShoulder(c, i, images, min_quality);
    if (std::isfinite(s)) shoulder.push_back(s);
  }
  if (shoulder.empty()) return false;
  std::nth_element(shoulder.begin(), shoulder.begin() + std::ptrdiff_t(shoulder.size() / 2), shoulder.end());
  return shoulder[shoulder.size() / 2] < kCoarseShoulder;
}

}  // namespace fvm::imaging
