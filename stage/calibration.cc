#include "stage/calibration.h"

#include <vector>

#include "stage/inverse_model.h"

namespace fvm::stage {

Eigen::MatrixXd Calibration::Correlation() const {
  const Eigen::VectorXd u = StandardUncertainty();
  Eigen::MatrixXd r = covariance;
  for (Eigen::Index i = 0; i < r.rows(); ++i) {
    for (Eigen::Index j = 0; j < r.cols(); ++j) r(i, j) = (u[i] > 0 && u[j] > 0) ? r(i, j) / (u[i] * u[j]) : 0.0;
  }
  return r;
}

TermValuesWithUncertainty TermValuesAt(const Calibration& calibration, const Eigen::Vector3d& q,
                                       const Eigen::Vector3d* reference) {
  const ParameterLayout& layout = calibration.layout;
  std::vector<double> all(layout.coefficients().size());
  layout.Expand(calibration.values.data(), all.data());
  TermValuesWithUncertainty out;
  layout.TermValues(all.data(), q, out.value.data());
  Eigen::MatrixXd d = layout.TermDerivative(q);
  if (reference != nullptr) {
    Eigen::Matrix<double, kNumErrorTerms, 1> at_reference;
    layout.TermValues(all.data(), *reference, at_reference.data());
    out.value -= at_reference;
    d -= layout.TermDerivative(*reference);
  }
  if (calibration.covariance.rows() == d.cols() && calibration.covariance.cols() == d.cols()) {
    out.u = (d * calibration.covariance * d.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  }
  return out;
}

Compensation CompensateCommand(const Calibration& calibration, const Eigen::Vector3d& nominal) {
  const ParameterLayout& layout = calibration.layout;
  const Eigen::Vector3d tool = layout.chain().tool_offset;
  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = layout.travel()[static_cast<size_t>(k)].min;
  const Eigen::Vector3d error_at_origin = Forward(layout, calibration.values, origin) - origin - tool;
  Compensation out;
  out.target = nominal + tool + error_at_origin;
  const InverseResult inverse = Inverse(layout, calibration.values.data(), out.target);
  out.command = inverse.command;
  out.converged = inverse.converged;
  return out;
}

CorrectedPoint Correct(const Calibration& calibration, const Eigen::Vector3d& free_point) {
  CorrectedPoint out;
  const Eigen::MatrixXd j = ForwardJacobian(calibration.layout, calibration.values.data(), free_point, &out.position);
  if (calibration.covariance.rows() == j.cols()) out.covariance = j * calibration.covariance * j.transpose();
  out.covariance += calibration.unmodelled_mm.cwiseAbs2().asDiagonal();
  return out;
}

FirstTileCompensation::FirstTileCompensation(const Calibration& calibration, StitchedFrame frame,
                                             const Eigen::Vector3d& first_tile)
    : calibration_(calibration) {
  frame_.first_tile = first_tile;
  origin_jacobian_ = ForwardJacobian(calibration.layout, calibration.values.data(), first_tile, &frame_.origin);
  const Eigen::Vector3d* reference = calibration.frame_reference ? &*calibration.frame_reference : nullptr;
  frame_.turn = FirstTileTurn(frame, calibration.layout, calibration.values.data(), first_tile, reference, &turn_jacobian_);
}

Eigen::Vector3d FirstTileCompensation::operator()(const Eigen::Vector3d& free_point, Eigen::MatrixXd* jacobian) const {
  Eigen::Vector3d p;
  const Eigen::MatrixXd j = ForwardJacobian(calibration_.layout, calibration_.values.data(), free_point, &p);
  if (jacobian) {
    *jacobian = frame_.turn * (j - origin_jacobian_);
    for (size_t k = 0; k < turn_jacobian_.size(); ++k) jacobian->col(static_cast<Eigen::Index>(k)) += turn_jacobian_[k] * (p - frame_.origin);
  }
  return frame_.Stitched(p);
}

CorrectedPoint FirstTileCompensation::Correct(const Eigen::Vector3d& free_point) const {
  CorrectedPoint out;
  Eigen::MatrixXd j;
  out.position = (*this)(free_point, &j);
  if (calibration_.covariance.rows() == j.cols()) out.covariance = j * calibration_.covariance * j.transpose();
  out.covariance += calibration_.unmodelled_mm.cwiseAbs2().asDiagonal();
  return out;
}

}  // namespace fvm::stage
