#include "artefacts/scan_correlated_errors.h"

#include <Eigen/QR>
#include <cmath>
#include <numbers>

#include "core/dense_decomposition.h"
#include "artefacts/scan_observations.h"
#include "stage/parameter_layout.h"

namespace fvm::artefacts {

namespace {

// The displacements' Jacobian J_i weighted as the fit weighs them, J_i^T W_i (n x 3), and J_i itself.
struct WeightedDisplacement {
  Eigen::MatrixXd weighted, jacobian;
};
WeightedDisplacement WeighDisplacement(const stage::Calibration& calibration, const stage::Observation& o, int index) {
  const Eigen::Vector3d from = o.from.value_or(o.command);
  WeightedDisplacement w;
  w.jacobian = stage::ForwardJacobian(calibration.layout, calibration.values.data(), o.command) -
               stage::ForwardJacobian(calibration.layout, calibration.values.data(), from);
  // The registrations' information as the fit weighs it: xy always, z where height-map tiles gave the pair a
  // height step.
  w.weighted = w.jacobian.transpose() * stage::ObservedInformation(o.covariance, index);
  return w;
}

}  // namespace

Eigen::MatrixXd FieldDistortionCovariance(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                          const std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>& sensitivity_mm,
                                          const Eigen::MatrixXd& field_covariance_px2) {
  const auto n = static_cast<Eigen::Index>(calibration.values.size());
  const Eigen::Index k = field_covariance_px2.rows();
  if (n == 0 || set.observations.empty() || k == 0) return Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n), pulled = Eigen::MatrixXd::Zero(n, k);
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const WeightedDisplacement w = WeighDisplacement(calibration, set.observations[i], static_cast<int>(i));
    normal += w.weighted * w.jacobian;
    pulled += w.weighted * sensitivity_mm[i];
  }
  const Eigen::MatrixXd response =
      Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(normal, "the scans' field distortion: the normal equations")
          .solve(pulled);
  return response * field_covariance_px2 * response.transpose();
}

ScanCorrelatedErrors ScanCorrelatedErrorCovariances(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                                    const std::vector<Eigen::Vector3d>& residuals, double pixel_mm,
                                                    double gain_u) {
  const auto n = static_cast<Eigen::Index>(calibration.values.size());
  const size_t m = set.observations.size();
  ScanCorrelatedErrors out{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  if (n == 0 || m == 0 || residuals.size() != m || !(pixel_mm > 0.0)) return out;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n), pulled = Eigen::MatrixXd::Zero(n, 2);
  std::vector<Eigen::MatrixXd> weighted;  // J_i^T W_i, n x 3
  std::vector<std::vector<size_t>> runs;  // runs of consecutive pairs: where a scan's residuals may be shifted
  for (size_t i = 0; i < m; ++i) {
    const stage::Observation& o = set.observations[i];
    const WeightedDisplacement w = WeighDisplacement(calibration, o, static_cast<int>(i));
    weighted.push_back(w.weighted);
    normal += w.weighted * w.jacobian;
    // The bias of a unit gain in each coordinate, in the displacement's millimetres (y up, the pixels' y down).
    const Eigen::Vector2d offset_px(o.measured.x() / pixel_mm, -o.measured.y() / pixel_mm);
    Eigen::Matrix<double, 3, 2> bias = Eigen::Matrix<double, 3, 2>::Zero();
    for (int c = 0; c < 2; ++c) {
      const double f = offset_px(c) - std::round(offset_px(c));
      bias(c, c) = -std::sin(2.0 * std::numbers::pi * f) / (2.0 * std::numbers::pi) * pixel_mm;
    }
    bias(1, 1) = -bias(1, 1);
    pulled += weighted.back() * bias;
    if (!ContinuesRun(set, i)) runs.emplace_back();
    runs.back().push_back(i);
  }
  // A coefficient these displacements do not see (none, once the rank treatment fixed them) gets no response.
  const auto solve = Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(normal, "the scans' sub-pixel bias: the gains' normal equations");
  const Eigen::MatrixXd gain_response = solve.solve(pulled);  // to k_x and k_y
  out.subpixel_bias = gain_u * gain_u * gain_response * gain_response.transpose();
  for (const std::vector<size_t>& run : runs) {
    for (size_t lag = 1; lag < run.size(); ++lag) {
      Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
      for (size_t k = 0; k < run.size(); ++k) g += weighted[run[k]] * residuals[run[(k + lag) % run.size()]];
      const Eigen::VectorXd response = solve.solve(g);
      out.misfit += response * response.transpose() / static_cast<double>(run.size());
    }
  }
  return out;
}

}  // namespace fvm::artefacts
