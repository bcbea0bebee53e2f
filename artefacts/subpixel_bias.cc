#include "artefacts/subpixel_bias.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <numbers>

#include "stage/parameter_layout.h"

namespace fvm::artefacts {

Eigen::MatrixXd SubpixelBiasCovariance(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                       double pixel_mm, double gain_u) {
  const auto n = static_cast<Eigen::Index>(calibration.values.size());
  const auto m = static_cast<Eigen::Index>(set.observations.size());
  if (n == 0 || m == 0 || !(pixel_mm > 0.0)) return Eigen::MatrixXd::Zero(n, n);
  // The fit linearised in xy, its weights the registrations' information (a displacement's turn, tens of
  // microradians, left out of the map): the coefficients move by (J^T W J)^-1 J^T W e for displacement errors e.
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n), pulled = Eigen::MatrixXd::Zero(n, 2);
  for (const stage::Observation& o : set.observations) {
    const Eigen::Vector3d from = o.from.value_or(o.command);
    const Eigen::MatrixXd j = (stage::ForwardJacobian(calibration.layout, calibration.values.data(), o.command) -
                               stage::ForwardJacobian(calibration.layout, calibration.values.data(), from)).topRows(2);
    const Eigen::MatrixXd jw = j.transpose() * o.covariance.topLeftCorner<2, 2>().inverse();
    normal += jw * j;
    // The bias of a unit gain, in the displacement's millimetres (y up, where the pixel frame's y is down).
    const Eigen::Vector2d offset_px(o.measured.x() / pixel_mm, -o.measured.y() / pixel_mm);
    Eigen::Matrix2d bias = Eigen::Matrix2d::Zero();
    for (int c = 0; c < 2; ++c) {
      const double f = offset_px(c) - std::round(offset_px(c));
      bias(c, c) = -std::sin(2.0 * std::numbers::pi * f) / (2.0 * std::numbers::pi) * pixel_mm;
    }
    bias(1, 1) = -bias(1, 1);
    pulled += jw * bias;
  }
  const Eigen::MatrixXd response = normal.ldlt().solve(pulled);  // the coefficients' response to k_x and k_y
  return gain_u * gain_u * response * response.transpose();
}

}  // namespace fvm::artefacts
