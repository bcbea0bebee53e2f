#include "stage/residual_field.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/dense_decomposition.h"

namespace fvm::stage {

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
  for (size_t i = 0; i < residuals_mm.size(); ++i) {
    const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(
        covariances[i], "the residual field: the covariance of centre " + std::to_string(i + 1));
    const Eigen::Vector3d gain = (variance / (variance + eig.eigenvalues().cwiseMax(0.0).array())).sqrt().matrix();
    field.offsets_mm[i] = eig.eigenvectors() * gain.asDiagonal() * eig.eigenvectors().transpose() * residuals_mm[i];
  }
  return field;
}

}  // namespace fvm::stage
