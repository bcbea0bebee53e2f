#pragma once
// One tracker station's reading of one point as a Ceres residual block (stage/multilateration.h): the point p and
// the station's position s (mm, common frame) are parameter blocks; with angles, so is a small rotation w of the
// station's frame away from its current rotation R, q = exp(w)^T R^T (p - s) in the station's own frame. Residuals
// are whitened by the noise model's sigmas: the range |q| alone, or range, azimuth and elevation ([Aguado 2016]
// eqs. 10-16). Derivatives by automatic differentiation.

#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <numbers>

#include "stage/multilateration.h"

namespace fvm::stage {

// The sigmas a reading is weighed by: the range's from the noise model (1 um for a noise-free one), the angles'
// constant (1 urad for a noise-free one).
struct ReadingSigmas {
  double range_mm = 1e-3;
  double azimuth_rad = 1e-6;
  double elevation_rad = 1e-6;
};

namespace station_reading_detail {

inline double ValueOf(double x) { return x; }
template <typename T, int N>
double ValueOf(const ceres::Jet<T, N>& x) {
  return x.a;
}

// Range residual of q (the point in the station's frame).
template <typename T>
T RangeResidual(const T* q, double range_mm, double sigma_mm) {
  using std::sqrt;
  return (sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]) - range_mm) / sigma_mm;
}

}  // namespace station_reading_detail

// Ranges only: the station's rotation does not change a range, so it is not a parameter.
struct StationRangeResidual {
  double range_mm;
  double sigma_mm;
  template <typename T>
  bool operator()(const T* point, const T* station, T* residual) const {
    const T q[3] = {point[0] - station[0], point[1] - station[1], point[2] - station[2]};
    residual[0] = station_reading_detail::RangeResidual(q, range_mm, sigma_mm);
    return true;
  }
};

// Range, azimuth and elevation, with the station's rotation increment w (rotation vector, rad).
struct StationBundleResidual {
  StationReading reading;
  ReadingSigmas sigmas;
  Eigen::Matrix3d rotation;  // R: the station's frame at the start of this solve

  template <typename T>
  bool operator()(const T* point, const T* station, const T* w, T* residual) const {
    using station_reading_detail::ValueOf;
    using std::atan2;
    using std::sqrt;
    const T d[3] = {point[0] - station[0], point[1] - station[1], point[2] - station[2]};
    T u[3];  // R^T (p - s)
    for (int r = 0; r < 3; ++r) u[r] = rotation(0, r) * d[0] + rotation(1, r) * d[1] + rotation(2, r) * d[2];
    const T minus_w[3] = {-w[0], -w[1], -w[2]};
    T q[3];  // exp(w)^T u
    ceres::AngleAxisRotatePoint(minus_w, u, q);
    residual[0] = station_reading_detail::RangeResidual(q, reading.range_mm, sigmas.range_mm);
    const double h2 = ValueOf(q[0]) * ValueOf(q[0]) + ValueOf(q[1]) * ValueOf(q[1]);
    if (h2 > 1e-18) {
      // The azimuth's difference wrapped to (-pi, pi] by a constant shift of whole turns, which leaves its
      // derivative alone.
      const T azimuth = atan2(q[1], q[0]);
      const double difference = ValueOf(azimuth) - reading.azimuth_rad;
      const double turns = difference - std::remainder(difference, 2.0 * std::numbers::pi);
      residual[1] = (azimuth - reading.azimuth_rad - turns) / sigmas.azimuth_rad;
      residual[2] = (atan2(q[2], sqrt(q[0] * q[0] + q[1] * q[1])) - reading.elevation_rad) / sigmas.elevation_rad;
    } else {  // straight up or down: the azimuth is undefined and the elevation does not move to first order
      residual[1] = T(0.0);
      residual[2] = T((std::atan2(ValueOf(q[2]), 0.0) - reading.elevation_rad) / sigmas.elevation_rad);
    }
    return true;
  }
};

// The residual block of one reading: 1 residual (point, station) without angles, 3 (point, station, rotation
// increment) with them.
inline std::unique_ptr<ceres::CostFunction> StationReadingCost(const StationReading& reading, const ReadingSigmas& sigmas,
                                                               const Eigen::Matrix3d& rotation, bool angles) {
  if (!angles) {
    return std::make_unique<ceres::AutoDiffCostFunction<StationRangeResidual, 1, 3, 3>>(
        new StationRangeResidual{reading.range_mm, sigmas.range_mm});
  }
  return std::make_unique<ceres::AutoDiffCostFunction<StationBundleResidual, 3, 3, 3, 3>>(
      new StationBundleResidual{reading, sigmas, rotation});
}

}  // namespace fvm::stage
