#pragma once
// A rigid pose: where a frame (a laser tracker, a part) sits in another, as translation + rotation vector.

#include <Eigen/Core>
#include <ceres/rotation.h>

namespace fvm::stage {

struct Pose {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // mm
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();     // axis-angle vector, rad

  // R = Rx(a) * Ry(b) * Rz(c): rotate about x, then the new y, then the new z (intrinsic XYZ Euler angles,
  // the tracker-pose convention of [Pérez 2019 Sensors] eq. 22).
  static Pose FromEulerXyzDegrees(const Eigen::Vector3d& translation, const Eigen::Vector3d& euler_deg);
  Eigen::Matrix3d Rotation() const;
};

// The cross-product matrix [v]x: Skew(v) w = v x w. A small rotation w moves a point at d by w x d = -Skew(d) w.
Eigen::Matrix3d Skew(const Eigen::Vector3d& v);

// Coordinates in the posed frame of a point given in the parent frame: R^T (p - t). The pose may be given as
// six scalars (translation, rotation vector) so Ceres can estimate it.
template <typename T>
Eigen::Matrix<T, 3, 1> ToPosedFrame(const T* pose6, const Eigen::Matrix<T, 3, 1>& p) {
  const T shifted[3] = {p[0] - pose6[0], p[1] - pose6[1], p[2] - pose6[2]};
  const T inverse_rotation[3] = {-pose6[3], -pose6[4], -pose6[5]};
  Eigen::Matrix<T, 3, 1> out;
  ceres::AngleAxisRotatePoint(inverse_rotation, shifted, out.data());
  return out;
}

}  // namespace fvm::stage
