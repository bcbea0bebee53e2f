#pragma once
// A laser tracker as a measuring instrument: its spherical coordinates and the noise of its readings.
//
// A tracker reads a range and two angles ([IJSIMM 2016] 4.4); its Cartesian coordinates are x = r cos(el) cos(az),
// y = r cos(el) sin(az), z = r sin(el) in its own frame. The published noise model ([IJSIMM 2016] eqs. 22-24,
// section 5) is normal and independent per spherical coordinate: range sigma a + b*L, azimuth and elevation
// sigma constant. Seen in Cartesian coordinates that is a 3x3 covariance per point, elongated across the beam
// (24 urad at 3 m is 72 um across, against 6 um along it), which is why identification weights each reading
// with it instead of treating the three coordinates alike.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace fvm::stage {

struct Spherical {
  double range_mm = 0.0;
  double azimuth_rad = 0.0;    // from +x towards +y
  double elevation_rad = 0.0;  // from the xy plane towards +z
};

Spherical ToSpherical(const Eigen::Vector3d& point);
Eigen::Vector3d FromSpherical(const Spherical& s);
// d(x, y, z) / d(range, azimuth, elevation) at s.
Eigen::Matrix3d SphericalJacobian(const Spherical& s);

struct TrackerNoise {
  std::string name = "published";
  double range_sigma_mm = 0.004;          // a: 4 um
  double range_sigma_per_mm = 0.8e-6;     // b: 0.8 um per metre of range
  double azimuth_sigma_rad = 24e-6;
  double elevation_sigma_rad = 24e-6;

  // "published" ([IJSIMM 2016] section 5, [Aguado 2017]): 24 urad, 4 um + 0.8 um/m; "ifm" and "adm": the interferometer
  // and absolute distance meter of [Aguado 2016] Table 3 as docs/commands/verify.md documents them; "none": a perfect tracker. Throws
  // std::invalid_argument listing the presets.
  static TrackerNoise Preset(std::string_view name);
  static std::vector<std::string> PresetNames();

  double RangeSigmaMm(double range_mm) const { return range_sigma_mm + range_sigma_per_mm * range_mm; }
  // Covariance (mm^2) of a reading at `point` in the tracker's frame: J diag(sr^2, sa^2, se^2) J^T.
  Eigen::Matrix3d Covariance(const Eigen::Vector3d& point) const;
  bool IsNoiseFree() const;
  // The reading of `point` (tracker frame, mm) with standard normal draws n_* scaled by the sigmas and added to its
  // range, azimuth and elevation ([IJSIMM 2016] eqs. 22-24); `point` itself, bit for bit, for a noise-free tracker.
  Eigen::Vector3d Perturb(const Eigen::Vector3d& point, double n_range, double n_azimuth, double n_elevation) const;
};

}  // namespace fvm::stage
