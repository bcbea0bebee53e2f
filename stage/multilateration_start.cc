#include "stage/multilateration_start.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/dense_decomposition.h"
#include "stage/tracker.h"

namespace fvm::stage {

void ThreeTwoOneFrame(const std::vector<Eigen::Vector3d>& stations, Eigen::Matrix3d* rotation, Eigen::Vector3d* translation) {
  if (stations.size() < 3) throw std::invalid_argument("the 3-2-1 frame needs three stations");
  const Eigen::Vector3d d1 = stations[1] - stations[0], d2 = stations[2] - stations[0];
  const Eigen::Vector3d e1 = d1.normalized();
  const Eigen::Vector3d v = d2 - d2.dot(e1) * e1;
  if (!(d1.norm() > 0) || !(v.norm() > 1e-9 * std::max(d1.norm(), d2.norm()))) {
    throw std::invalid_argument("stations 1, 2 and 3 lie on one line (or coincide): they cannot define the frame "
                                "(station 1 at the origin, 2 on x, 3 in the xy plane); reorder the stations");
  }
  const Eigen::Vector3d e2 = v.normalized();
  const Eigen::Vector3d e3 = e1.cross(e2);
  rotation->row(0) = e1.transpose();
  rotation->row(1) = e2.transpose();
  rotation->row(2) = e3.transpose();
  *translation = -(*rotation) * stations[0];
}

Eigen::Vector3d TrilaterateClosedForm(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges) {
  return Trilaterate(stations, ranges, nullptr);
}

Eigen::Vector3d Trilaterate(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges,
                            Eigen::Vector3d* mirror) {
  const size_t n = stations.size();
  if (n < 3 || ranges.size() != n) throw std::invalid_argument("trilateration needs three or more stations with a range each");
  const Eigen::Index rows = static_cast<Eigen::Index>(n - 1);
  Eigen::MatrixXd a(rows, 3);
  Eigen::VectorXd b(rows);
  for (size_t i = 1; i < n; ++i) {
    const Eigen::Vector3d d = stations[i] - stations[0];
    a.row(static_cast<Eigen::Index>(i - 1)) = 2.0 * d.transpose();
    b[static_cast<Eigen::Index>(i - 1)] = ranges[0] * ranges[0] - ranges[i] * ranges[i] + d.squaredNorm();
  }
  const auto svd = Decompose<Eigen::JacobiSVD<Eigen::MatrixXd>>(a, "multilateration start: the range differences",
                                                                Eigen::ComputeFullV | Eigen::ComputeThinU);
  const Eigen::VectorXd sv = svd.singularValues();
  if (n >= 4 && sv.size() == 3 && sv[2] > 1e-6 * sv[0]) {
    const Eigen::Vector3d p = stations[0] + svd.solve(b);
    if (mirror != nullptr) *mirror = p;
    return p;
  }
  // In the stations' plane, then the height above it.
  const Eigen::Matrix<double, 3, 2> plane = svd.matrixV().leftCols(2);
  Eigen::Vector3d normal = svd.matrixV().col(2);
  const Eigen::Vector2d in_plane =
      Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(a * plane, "multilateration start: the stations' plane").solve(b);
  const Eigen::Vector3d x = plane * in_plane;
  double h2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = stations[i] - stations[0];
    h2 += ranges[i] * ranges[i] - (x - d).squaredNorm();
  }
  h2 /= static_cast<double>(n);
  // The side: where (s2 - s1) x (s3 - s1) of the first three stations points (they appear counter-clockwise from
  // the point); with those on one line, towards +z, +y or +x.
  const Eigen::Vector3d n0 = (stations[1] - stations[0]).cross(stations[2] - stations[0]);
  const double eps = 1e-9;
  const bool flip = n0.norm() > 1e-9 * (stations[1] - stations[0]).squaredNorm() ? normal.dot(n0) < 0
                    : std::abs(normal.z()) > eps                                 ? normal.z() < 0
                    : std::abs(normal.y()) > eps                                 ? normal.y() < 0
                                                                                 : normal.x() < 0;
  if (flip) normal = -normal;
  const double h = std::sqrt(std::max(0.0, h2));
  if (mirror != nullptr) *mirror = stations[0] + x - h * normal;
  return stations[0] + x + h * normal;
}

std::vector<Eigen::Vector3d> StartStationsFromAngles(const MultilaterationProblem& p) {
  const size_t m = p.station_names.size(), np = p.point_ids.size();
  // Cartesian reading of each point by each station (NaN when not read).
  std::vector<std::vector<Eigen::Vector3d>> local(m, std::vector<Eigen::Vector3d>(np, Eigen::Vector3d::Constant(NAN)));
  for (const StationReading& r : p.readings) {
    if (!r.has_angles) {
      throw std::invalid_argument("starting stations from the angles needs azimuth and elevation in every reading");
    }
    local[static_cast<size_t>(r.station)][static_cast<size_t>(r.point)] = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
  }
  std::vector<Eigen::Vector3d> out(m, Eigen::Vector3d::Zero());
  for (size_t i = 1; i < m; ++i) {
    std::vector<Eigen::Vector3d> from, to;
    for (size_t j = 0; j < np; ++j) {
      if (local[i][j].allFinite() && local[0][j].allFinite()) {
        from.push_back(local[i][j]);
        to.push_back(local[0][j]);
      }
    }
    Eigen::Vector3d cf = Eigen::Vector3d::Zero(), ct = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < from.size(); ++k) {
      cf += from[k];
      ct += to[k];
    }
    if (from.size() < 3) {
      throw std::invalid_argument(fmt::format("station {} shares {} points with station {}: a start from the angles "
                                              "needs 3; give starting positions (--stations)",
                                              p.station_names[i], from.size(), p.station_names[0]));
    }
    cf /= static_cast<double>(from.size());
    ct /= static_cast<double>(from.size());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < from.size(); ++k) h += (from[k] - cf) * (to[k] - ct).transpose();
    const auto svd = Decompose<Eigen::JacobiSVD<Eigen::Matrix3d>>(h, "multilateration start: a station's rotation",
                                                               Eigen::ComputeFullU | Eigen::ComputeFullV);
    if (!(svd.singularValues()[1] > 1e-9 * svd.singularValues()[0])) {
      throw std::invalid_argument(fmt::format("the points station {} shares with station {} lie on one line: a start "
                                              "from the angles needs them spread; give starting positions (--stations)",
                                              p.station_names[i], p.station_names[0]));
    }
    Eigen::Matrix3d fix = Eigen::Matrix3d::Identity();
    fix(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d r = svd.matrixV() * fix * svd.matrixU().transpose();
    out[i] = ct - r * cf;  // where station i's origin lands in station 1's frame
  }
  return out;
}

double StationRotationMisfit(const MultilaterationProblem& p, const std::vector<Eigen::Vector3d>& stations,
                             const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Matrix3d>* rotations) {
  double misfit = 0;
  if (rotations != nullptr) rotations->assign(stations.size(), Eigen::Matrix3d::Identity());
  for (size_t i = 0; i < stations.size(); ++i) {
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (const StationReading& r : p.readings) {
      if (static_cast<size_t>(r.station) != i) continue;
      const Eigen::Vector3d local = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
      h += local * (points[static_cast<size_t>(r.point)] - stations[i]).transpose();
    }
    const auto svd = Decompose<Eigen::JacobiSVD<Eigen::Matrix3d>>(h, "multilateration start: a station's rotation",
                                                               Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d fix = Eigen::Matrix3d::Identity();
    fix(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d rotation = svd.matrixV() * fix * svd.matrixU().transpose();
    if (rotations != nullptr) (*rotations)[i] = rotation;
    for (const StationReading& r : p.readings) {
      if (static_cast<size_t>(r.station) != i) continue;
      const Eigen::Vector3d local = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
      misfit += (rotation * local - (points[static_cast<size_t>(r.point)] - stations[i])).squaredNorm();
    }
  }
  return misfit;
}

}  // namespace fvm::stage
