#include "stage/pose.h"

#include <Eigen/Geometry>
#include <numbers>

namespace fvm::stage {

Pose Pose::FromEulerXyzDegrees(const Eigen::Vector3d& translation, const Eigen::Vector3d& euler_deg) {
  const Eigen::Vector3d a = euler_deg * std::numbers::pi / 180.0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  const Eigen::AngleAxisd aa(r);
  return Pose{translation, aa.axis() * aa.angle()};
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d Pose::Rotation() const {
  Eigen::Matrix3d r;
  ceres::AngleAxisToRotationMatrix(rotation.data(), ceres::ColumnMajorAdapter3x3(r.data()));
  return r;
}

}  // namespace fvm::stage
