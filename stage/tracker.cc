#include "stage/tracker.h"

#include <cmath>
#include <stdexcept>

namespace fvm::stage {

Spherical ToSpherical(const Eigen::Vector3d& p) {
  const double horizontal = std::hypot(p.x(), p.y());
  return {p.norm(), std::atan2(p.y(), p.x()), std::atan2(p.z(), horizontal)};
}

Eigen::Vector3d FromSpherical(const Spherical& s) {
  const double c = std::cos(s.elevation_rad);
  return s.range_mm * Eigen::Vector3d(c * std::cos(s.azimuth_rad), c * std::sin(s.azimuth_rad), std::sin(s.elevation_rad));
}

Eigen::Matrix3d SphericalJacobian(const Spherical& s) {
  const double ca = std::cos(s.azimuth_rad), sa = std::sin(s.azimuth_rad);
  const double ce = std::cos(s.elevation_rad), se = std::sin(s.elevation_rad);
  const double r = s.range_mm;
  Eigen::Matrix3d j;
  j << ce * ca, -r * ce * sa, -r * se * ca,  //
      ce * sa, r * ce * ca, -r * se * sa,    //
      se, 0.0, r * ce;
  return j;
}

std::vector<std::string> TrackerNoise::PresetNames() { return {"published", "ifm", "adm", "none"}; }

TrackerNoise TrackerNoise::Preset(std::string_view name) {
  TrackerNoise t;
  t.name = std::string(name);
  if (name == "published") return t;
  if (name == "ifm") {
    // [Aguado 2016] Table 3, tracker A (interferometer): angular accuracy +-10 um/m across the beam, i.e. 10 urad. The
    // table gives no range figure for it; an interferometer's 0.5 um + 0.4 um/m is assumed (docs/commands/verify.md).
    t.azimuth_sigma_rad = t.elevation_sigma_rad = 10e-6;
    t.range_sigma_mm = 0.0005;
    t.range_sigma_per_mm = 0.4e-6;
    return t;
  }
  if (name == "adm") {
    // [Aguado 2016] Table 3, tracker C (absolute distance meter): 20 um + 5 um/m across the beam, 16 um + 0.8 um/m
    // along it.
    t.azimuth_sigma_rad = t.elevation_sigma_rad = 5e-6;
    t.range_sigma_mm = 0.016;
    t.range_sigma_per_mm = 0.8e-6;
    return t;
  }
  if (name == "none") {
    t.range_sigma_mm = t.range_sigma_per_mm = t.azimuth_sigma_rad = t.elevation_sigma_rad = 0.0;
    return t;
  }
  throw std::invalid_argument("unknown tracker '" + std::string(name) + "': use published, ifm, adm or none");
}

bool TrackerNoise::IsNoiseFree() const {
  return range_sigma_mm == 0.0 && range_sigma_per_mm == 0.0 && azimuth_sigma_rad == 0.0 && elevation_sigma_rad == 0.0;
}

Eigen::Matrix3d TrackerNoise::Covariance(const Eigen::Vector3d& point) const {
  const Spherical s = ToSpherical(point);
  const Eigen::Matrix3d j = SphericalJacobian(s);
  const double sr = RangeSigmaMm(s.range_mm);
  const Eigen::Vector3d variances(sr * sr, azimuth_sigma_rad * azimuth_sigma_rad, elevation_sigma_rad * elevation_sigma_rad);
  return j * variances.asDiagonal() * j.transpose();
}

Eigen::Vector3d TrackerNoise::Perturb(const Eigen::Vector3d& point, double n_range, double n_azimuth,
                                      double n_elevation) const {
  if (IsNoiseFree()) return point;
  Spherical s = ToSpherical(point);
  s.range_mm += RangeSigmaMm(s.range_mm) * n_range;
  s.azimuth_rad += azimuth_sigma_rad * n_azimuth;
  s.elevation_rad += elevation_sigma_rad * n_elevation;
  return FromSpherical(s);
}

}  // namespace fvm::stage
