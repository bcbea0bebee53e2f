#include "stage/calibration.h"

namespace fvm::stage {

Eigen::MatrixXd Calibration::Correlation() const {
  const Eigen::VectorXd u = StandardUncertainty();
  Eigen::MatrixXd r = covariance;
  for (Eigen::Index i = 0; i < r.rows(); ++i) {
    for (Eigen::Index j = 0; j < r.cols(); ++j) r(i, j) = (u[i] > 0 && u[j] > 0) ? r(i, j) / (u[i] * u[j]) : 0.0;
  }
  return r;
}

CorrectedPoint Correct(const Calibration& calibration, const Eigen::Vector3d& free_point) {
  CorrectedPoint out;
  const Eigen::MatrixXd j = ForwardJacobian(calibration.layout, calibration.values.data(), free_point, &out.position);
  if (calibration.covariance.rows() == j.cols()) out.covariance = j * calibration.covariance * j.transpose();
  return out;
}

}  // namespace fvm::stage
