#include "imaging/focus_peak.h"

#include <algorithm>
#include <cmath>

namespace fvm::imaging {
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

}  // namespace fvm::imaging
