#include "imaging/field_distortion.h"
#include "core/dense_decomposition.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

namespace fvm::imaging {
namespace {

// One monomial of one component of a term: coefficient * x^i y^j added to d_x (component 0) or d_y (1).
struct FieldMonomial {
  int component, i, j;
  double factor;
};
struct FieldTerm {
  std::string name;
  int degree;
  std::vector<FieldMonomial> monomials;
};

std::string MonomialName(int component, int i, int j) {
  // Appended piece by piece, not `"x" + std::to_string(i)`: GCC 12 inlines operator+(const char*, string&&) and
  // warns falsely of overlapping memcpy of 2^63 bytes (-Wrestrict, GCC bug 105329; the Release build's only warning).
  std::string name = component == 0 ? "dx_" : "dy_";
  if (i > 0) {
    name += 'x';
    if (i > 1) name += std::to_string(i);
  }
  if (j > 0) {
    name += 'y';
    if (j > 1) name += std::to_string(j);
  }
  return name;
}

// The radial and tangential terms of one degree, then its monomials, each kept only when the terms before it do
// not already span it (the monomials of one degree are the coordinates: the rank test is exact).
std::vector<FieldTerm> TermsOfDegree(int degree) {
  std::vector<FieldTerm> candidates;
  if (degree == 2) {
    candidates.push_back({"p1", 2, {{0, 1, 1, 2.0}, {1, 2, 0, 1.0}, {1, 0, 2, 3.0}}});
    candidates.push_back({"p2", 2, {{0, 2, 0, 3.0}, {0, 0, 2, 1.0}, {1, 1, 1, 2.0}}});
  } else if (degree == 3) {
    candidates.push_back({"k1", 3, {{0, 3, 0, 1.0}, {0, 1, 2, 1.0}, {1, 2, 1, 1.0}, {1, 0, 3, 1.0}}});
  } else if (degree == 5) {
    candidates.push_back({"k2", 5, {{0, 5, 0, 1.0}, {0, 3, 2, 2.0}, {0, 1, 4, 1.0}, {1, 4, 1, 1.0}, {1, 2, 3, 2.0},
                                    {1, 0, 5, 1.0}}});
  }
  for (int component = 0; component < 2; ++component) {
    for (int j = 0; j <= degree; ++j) {
      const int i = degree - j;
      candidates.push_back({MonomialName(component, i, j), degree, {{component, i, j, 1.0}}});
    }
  }
  const int dims = 2 * (degree + 1);  // coordinates: component * (degree + 1) + j
  std::vector<FieldTerm> kept;
  Eigen::MatrixXd span(dims, 0);
  for (const FieldTerm& term : candidates) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(dims);
    for (const FieldMonomial& m : term.monomials) v(m.component * (degree + 1) + m.j) += m.factor;
    Eigen::MatrixXd trial(dims, span.cols() + 1);
    trial << span, v;
    if (Decompose<Eigen::FullPivLU<Eigen::MatrixXd>>(trial, "the field terms' span").rank() > span.cols()) {
      span = trial;
      kept.push_back(term);
    }
  }
  return kept;
}

const std::vector<FieldTerm>& Terms(int order) {
  if (order < 2 || order > kMaxDistortionOrder) {
    throw std::invalid_argument("field distortion: order " + std::to_string(order) + " outside 2.." +
                                std::to_string(kMaxDistortionOrder) +
                                " (below 2 is the linear part no overlap can tell; above, the overlaps cannot)");
  }
  // Built once for every order (thread-safe static initialisation), read without a lock from then on.
  static const std::vector<std::vector<FieldTerm>> all = [] {
    std::vector<std::vector<FieldTerm>> by_order(kMaxDistortionOrder + 1);
    for (int o = 2; o <= kMaxDistortionOrder; ++o) {
      for (int degree = 2; degree <= o; ++degree) {
        for (FieldTerm& t : TermsOfDegree(degree)) by_order[static_cast<size_t>(o)].push_back(std::move(t));
      }
    }
    return by_order;
  }();
  return all[static_cast<size_t>(order)];
}

using Powers = std::array<double, kMaxDistortionOrder + 1>;

// x^p for p = 0..order at normalised x, averaged over the kernel's offsets v / s about x: the mean of (x + v)^p is
// sum over even k of binomial(p, k) x^(p - k) m_k / s^k (odd moments vanish).
Powers AveragedPowers(double x, double s, const FieldKernel& kernel, int order) {
  Powers plain{};
  plain[0] = 1.0;
  for (int p = 1; p <= order; ++p) plain[p] = plain[p - 1] * x;
  if (kernel.m2 == 0.0 && kernel.m4 == 0.0 && kernel.m6 == 0.0) return plain;
  const std::array<double, 7> moment = {1.0, 0.0, kernel.m2 / (s * s), 0.0, kernel.m4 / std::pow(s, 4), 0.0,
                                        kernel.m6 / std::pow(s, 6)};
  Powers averaged{};
  for (int p = 0; p <= order; ++p) {
    double binomial = 1.0;  // binomial(p, k), k = 0, 1, ...
    for (int k = 0; k <= p; ++k) {
      averaged[p] += binomial * plain[p - k] * moment[static_cast<size_t>(k)];
      binomial = binomial * (p - k) / (k + 1);
    }
  }
  return averaged;
}

}  // namespace

const std::vector<std::string>& FieldDistortionTermNames(int order) {
  Terms(order);  // throws outside 2..kMaxDistortionOrder
  static const std::vector<std::vector<std::string>> names = [] {
    std::vector<std::vector<std::string>> by_order(kMaxDistortionOrder + 1);
    for (int o = 2; o <= kMaxDistortionOrder; ++o) {
      for (const FieldTerm& t : Terms(o)) by_order[static_cast<size_t>(o)].push_back(t.name);
    }
    return by_order;
  }();
  return names[static_cast<size_t>(order)];
}

std::vector<int> FieldDistortionStretchTerms(int order) {
  const std::vector<FieldTerm>& terms = Terms(order);
  std::vector<int> held;
  for (size_t t = 0; t < terms.size(); ++t) {
    for (const FieldMonomial& m : terms[t].monomials) {
      const int power = m.i + m.j;
      if (power >= 3 && power % 2 == 1 && (m.i == 0 || m.j == 0)) {
        held.push_back(static_cast<int>(t));
        break;
      }
    }
  }
  return held;
}

void FieldDistortion::Check() const {
  if (order == 0) return;
  const size_t k = Terms(order).size();
  if (static_cast<size_t>(coefficients.size()) != k) {
    throw std::invalid_argument("field distortion of order " + std::to_string(order) + ": " + std::to_string(k) +
                                " coefficients expected, " + std::to_string(coefficients.size()) + " given");
  }
  if (!(width_px > 0 && height_px > 0)) throw std::invalid_argument("field distortion: tile size not positive");
  if (covariance.size() != 0 && (covariance.rows() != coefficients.size() || covariance.cols() != coefficients.size())) {
    throw std::invalid_argument("field distortion: covariance does not match the coefficients");
  }
}

Eigen::Matrix<double, 2, Eigen::Dynamic> FieldDistortion::Basis(const Eigen::Vector2d& pixel,
                                                                const FieldKernel& kernel) const {
  if (order == 0) return Eigen::Matrix<double, 2, Eigen::Dynamic>(2, 0);
  const std::vector<FieldTerm>& terms = Terms(order);
  const double s = 0.5 * width_px;
  const Powers xp = AveragedPowers((pixel.x() - 0.5 * (width_px - 1)) / s, s, kernel, order);
  const Powers yp = AveragedPowers((pixel.y() - 0.5 * (height_px - 1)) / s, s, kernel, order);
  Eigen::Matrix<double, 2, Eigen::Dynamic> b = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, terms.size());
  for (size_t t = 0; t < terms.size(); ++t) {
    for (const FieldMonomial& m : terms[t].monomials) b(m.component, t) += m.factor * xp[m.i] * yp[m.j];
  }
  return b;
}

Eigen::Vector2d FieldDistortion::Displacement(const Eigen::Vector2d& pixel, const FieldKernel& kernel) const {
  if (order == 0) return Eigen::Vector2d::Zero();
  // Basis(pixel) * coefficients without the allocation: resampling a tile calls this millions of times.
  const std::vector<FieldTerm>& terms = Terms(order);
  const double s = 0.5 * width_px;
  const Powers xp = AveragedPowers((pixel.x() - 0.5 * (width_px - 1)) / s, s, kernel, order);
  const Powers yp = AveragedPowers((pixel.y() - 0.5 * (height_px - 1)) / s, s, kernel, order);
  double d[2] = {0.0, 0.0};
  for (size_t t = 0; t < terms.size(); ++t) {
    const double c = coefficients(static_cast<Eigen::Index>(t));
    for (const FieldMonomial& m : terms[t].monomials) d[m.component] += c * m.factor * xp[m.i] * yp[m.j];
  }
  return {d[0], d[1]};
}

Eigen::Vector2d FieldDistortion::RawPixel(const Eigen::Vector2d& undistorted_pixel) const {
  // u = u' - d(u): d changes by well under a pixel per pixel, so the iteration contracts fast.
  Eigen::Vector2d u = undistorted_pixel;
  for (int k = 0; k < 8; ++k) u = undistorted_pixel - Displacement(u);
  return u;
}

double FieldDistortion::LargestDisplacementPx(Eigen::Vector2d* where) const {
  double largest = 0.0;
  for (int j = 0; j <= 32; ++j) {
    for (int i = 0; i <= 32; ++i) {
      const Eigen::Vector2d u(i * (width_px - 1) / 32.0, j * (height_px - 1) / 32.0);
      const double n = Displacement(u).norm();
      if (n > largest) {
        largest = n;
        if (where) *where = u;
      }
    }
  }
  return largest;
}

double FieldDistortion::DisplacementSigmaPx() const {
  if (order == 0 || covariance.size() == 0) return 0.0;
  double sum = 0.0;
  int n = 0;
  for (int j = 0; j <= 16; ++j) {
    for (int i = 0; i <= 16; ++i) {
      const auto b = Basis(Eigen::Vector2d(i * (width_px - 1) / 16.0, j * (height_px - 1) / 16.0));
      sum += (b * covariance * b.transpose()).trace() / 2.0;
      ++n;
    }
  }
  return std::sqrt(sum / n);
}

}  // namespace fvm::imaging
