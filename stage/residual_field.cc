#include "stage/residual_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/dense_decomposition.h"

namespace fvm::stage {

namespace {

// The component of `residual` along each principal axis of `covariance` (variance l) scaled by sqrt(s^2 / (s^2 + l)).
Eigen::Vector3d ShrunkForNoise(const Eigen::Vector3d& residual, const Eigen::Matrix3d& covariance, double variance,
                               size_t index) {
  const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(
      covariance, "the residual field: the covariance of point " + std::to_string(index + 1));
  const Eigen::Vector3d gain = (variance / (variance + eig.eigenvalues().cwiseMax(0.0).array())).sqrt().matrix();
  return eig.eigenvectors() * gain.asDiagonal() * eig.eigenvectors().transpose() * residual;
}

// The field's power per direction in the estimation error's span, the same in each: components a_j ~ N(0, f + k_j)
// with k_j known (estimation error and noise), f by Paule and Mandel's moment equation sum a_j^2 / (f + k_j) = m
// [Paule 1982], whose left side falls with f: zero when the components are no larger than their known variances.
double FieldPowerAlong(const std::vector<double>& along, const std::vector<double>& known) {
  const auto excess = [&](double f) {
    double q = 0;
    for (size_t j = 0; j < along.size(); ++j) q += along[j] * along[j] / (f + known[j]);
    return q - static_cast<double>(along.size());
  };
  if (along.empty() || !(excess(0.0) > 0)) return 0.0;
  double lo = 0, hi = 0;
  for (size_t j = 0; j < along.size(); ++j) hi = std::max(hi, along[j] * along[j]);  // excess(max a_j^2) <= 0
  for (int i = 0; i < 100 && hi - lo > 1e-12 * hi; ++i) (excess(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

}  // namespace

ResidualField ShrunkResidualField(const std::vector<Eigen::Vector3d>& residuals_mm,
                                  const std::vector<Eigen::Matrix3d>& covariances) {
  if (residuals_mm.size() != covariances.size()) {
    throw std::invalid_argument("a residual field needs one covariance per residual");
  }
  ResidualField field;
  field.offsets_mm.assign(residuals_mm.size(), Eigen::Vector3d::Zero());
  if (residuals_mm.empty()) return field;
  double excess = 0;
  for (size_t i = 0; i < residuals_mm.size(); ++i) excess += residuals_mm[i].squaredNorm() - covariances[i].trace();
  const double variance = std::max(0.0, excess / (3.0 * static_cast<double>(residuals_mm.size())));
  field.sigma_mm = std::sqrt(variance);
  if (!(variance > 0)) return field;
  for (size_t i = 0; i < residuals_mm.size(); ++i) field.offsets_mm[i] = ShrunkForNoise(residuals_mm[i], covariances[i], variance, i);
  return field;
}

ResidualField HeldOutResidualField(const std::vector<Eigen::Vector3d>& residuals_mm,
                                   const std::vector<Eigen::Matrix3d>& noise_covariances,
                                   const std::vector<std::vector<Eigen::Vector3d>>& estimation_errors_mm, int dimension) {
  const size_t n = residuals_mm.size();
  if (noise_covariances.size() != n) throw std::invalid_argument("a residual field needs one covariance per residual");
  for (const std::vector<Eigen::Vector3d>& e : estimation_errors_mm) {
    if (e.size() != n) throw std::invalid_argument("a residual field needs each run's error at every residual");
  }
  ResidualField field;
  field.offsets_mm.assign(n, Eigen::Vector3d::Zero());
  if (n == 0) return field;
  const Eigen::Index rows = 3 * static_cast<Eigen::Index>(n);
  const Eigen::Index runs = static_cast<Eigen::Index>(estimation_errors_mm.size());
  Eigen::VectorXd r(rows);
  double power = 0, noise = 0;
  for (size_t p = 0; p < n; ++p) {
    r.segment<3>(3 * static_cast<Eigen::Index>(p)) = residuals_mm[p];
    power += residuals_mm[p].squaredNorm();
    noise += noise_covariances[p].trace();
  }
  double estimation = 0;  // tr Cov d
  if (runs > 1 && dimension > 0) {
    // The runs' deviations about their mean, scaled so that U U^T is their covariance; its principal directions
    // from the runs' Gram matrix U^T U (runs x runs, however many points).
    Eigen::MatrixXd u(rows, runs);
    for (Eigen::Index k = 0; k < runs; ++k) {
      const std::vector<Eigen::Vector3d>& run = estimation_errors_mm[static_cast<size_t>(k)];
      for (size_t p = 0; p < n; ++p) u.block<3, 1>(3 * static_cast<Eigen::Index>(p), k) = run[p];
    }
    u = (u.colwise() - u.rowwise().mean()) / std::sqrt(static_cast<double>(runs - 1));
    estimation = u.squaredNorm();
    // The directions from the first runs only, enough for the few dozen a model has: a Gram matrix of 1000 runs
    // would cost more than the runs themselves.
    const Eigen::Index used = std::min<Eigen::Index>(runs, std::max(200, 4 * dimension));
    const double rescale = std::sqrt(static_cast<double>(runs - 1) / static_cast<double>(std::max<Eigen::Index>(used - 1, 1)));
    const Eigen::MatrixXd first = u.leftCols(used) * rescale;  // their covariance from those runs
    const auto gram_eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>>(
        Eigen::MatrixXd(first.transpose() * first), "the held-out field: the runs' Gram matrix");  // ascending
    // Along each leading direction (unit, estimation variance l_j, the readings' noise n_j there) the residual's
    // component a_j = field + estimation error + noise.
    struct Direction {
      Eigen::VectorXd axis;
      double estimation = 0, noise = 0, along = 0;
    };
    std::vector<Direction> directions;
    const Eigen::Index m = std::min<Eigen::Index>(dimension, used);
    for (Eigen::Index j = used - 1; j >= used - m; --j) {
      const double l = gram_eig.eigenvalues()[j];
      if (!(l > 1e-12 * gram_eig.eigenvalues()[used - 1]) || !(l > 0)) break;
      Direction d{first * gram_eig.eigenvectors().col(j) / std::sqrt(l), l, 0.0, 0.0};
      for (size_t p = 0; p < n; ++p) {
        const Eigen::Index at = 3 * static_cast<Eigen::Index>(p);
        d.noise += d.axis.segment<3>(at).dot(noise_covariances[p] * d.axis.segment<3>(at));
      }
      d.along = d.axis.dot(r);
      directions.push_back(std::move(d));
    }
    std::vector<double> along, known;
    for (const Direction& d : directions) along.push_back(d.along), known.push_back(d.estimation + d.noise);
    const double f = FieldPowerAlong(along, known);
    // Each component scaled to keep the expected power of the field and the noise, sqrt((f + n) / (f + n + l)).
    Eigen::VectorXd removed = Eigen::VectorXd::Zero(rows);
    for (const Direction& d : directions) {
      const double keep = std::sqrt((f + d.noise) / (f + d.noise + d.estimation));
      removed += d.axis * ((1.0 - keep) * d.along);
    }
    r -= removed;
  }
  const double variance = std::max(0.0, (power - noise - estimation) / static_cast<double>(rows));
  field.sigma_mm = std::sqrt(variance);
  if (!(variance > 0)) return field;
  for (size_t p = 0; p < n; ++p) {
    field.offsets_mm[p] = ShrunkForNoise(r.segment<3>(3 * static_cast<Eigen::Index>(p)), noise_covariances[p], variance, p);
  }
  return field;
}

}  // namespace fvm::stage
