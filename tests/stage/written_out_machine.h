#pragma once
// A machine tool written out independently of the library, for the tests that must not share a mistake with its
// kinematics or its simulator: an XFYZ machine of [IJSIMM 2016]'s workspace read by a laser tracker, the readings
// from [Aguado 2016] eq. 1 written out (last term X) with error functions that no polynomial can take (ball-screw-like
// sines on top of cubics), and the tracker's noise on its own coordinates from [IJSIMM 2016] eqs. 22-24.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "stage/machine_verification.h"
#include "stage/tracker.h"

namespace fvm::stage::testing {

inline constexpr double kPi = 3.14159265358979323846;
inline const Eigen::Vector3d kWorkspace(2500.0, 1500.0, 1200.0);  // [IJSIMM 2016] section 5
inline const Eigen::Vector3d kTool(0.0, 0.0, 100.0);

inline Eigen::Matrix3d SmallRotation(const Eigen::Vector3d& e) {
  Eigen::Matrix3d r;
  r << 1, -e.z(), e.y(), e.z(), 1, -e.x(), -e.y(), e.x(), 1;
  return r;
}

inline Eigen::Matrix3d EulerXyz(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d a = deg * kPi / 180.0;
  return (Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

// The 21 error values at q, named as [Aguado 2016] names them.
struct Errors {
  Eigen::Vector3d x_t, y_t, z_t, x_r, y_r, z_r;
  double xwy = 0, xwz = 0, ywz = 0;
};

// X_LT = R_LT^T (R_X^-1 (R_Y (R_Z T + Z) + Y - X) - T_LT), small-angle matrices as [Aguado 2016] writes them.
inline Eigen::Vector3d SeedReading(const Errors& e, const Eigen::Vector3d& q, const Eigen::Matrix3d& r_lt, const Eigen::Vector3d& t_lt) {
  const Eigen::Vector3d xv(-q.x() + e.x_t.x(), e.x_t.y(), e.x_t.z());
  const Eigen::Vector3d yv(e.y_t.x() - q.y() * e.xwy, q.y() + e.y_t.y(), e.y_t.z());
  const Eigen::Vector3d zv(e.z_t.x() - q.z() * e.xwz, e.z_t.y() - q.z() * e.ywz, q.z() + e.z_t.z());
  const Eigen::Vector3d part =
      SmallRotation(e.x_r).inverse() * (SmallRotation(e.y_r) * (SmallRotation(e.z_r) * kTool + zv) + yv - xv);
  return r_lt.transpose() * (part - t_lt);
}

// Truth: per term a cubic plus a sine, zero at the axis origin. Positioning gets a 37 mm ball-screw period.
struct Truth {
  std::array<std::array<double, 3>, 21> cubic{};
  std::array<double, 21> amplitude{}, period{}, phase{};

  double Term(int t, double q, double length) const {
    const double u = q / length;
    const double poly = cubic[t][0] * u + cubic[t][1] * u * u + cubic[t][2] * u * u * u;
    if (amplitude[t] == 0.0) return poly;
    return poly + amplitude[t] * (std::sin(2 * kPi * q / period[t] + phase[t]) - std::sin(phase[t]));
  }
  Errors At(const Eigen::Vector3d& q) const {
    Errors e;
    Eigen::Vector3d* vectors[6] = {&e.x_t, &e.x_r, &e.y_t, &e.y_r, &e.z_t, &e.z_r};
    for (int axis = 0; axis < 3; ++axis) {
      for (int c = 0; c < 6; ++c) (*vectors[2 * axis + c / 3])[c % 3] = Term(6 * axis + c, q[axis], kWorkspace[axis]);
    }
    e.xwy = Term(18, 0, 1);  // squareness: constants (cubic[.][0] used as the value)
    e.xwz = Term(19, 0, 1);
    e.ywz = Term(20, 0, 1);
    return e;
  }
};

inline Truth MakeTruth(unsigned seed, bool polynomial_only, double scale = 1.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Truth t;
  for (int term = 0; term < 18; ++term) {
    const bool rotation = term % 6 >= 3;
    const double size = rotation ? scale * 1.5e-5 : scale * 0.012;  // 15 urad, 12 um per power at scale 1
    for (double& c : t.cubic[static_cast<size_t>(term)]) c = size * unit(rng);
    if (polynomial_only) continue;
    const bool positioning = term % 6 < 3 && term % 6 == term / 6;
    t.amplitude[static_cast<size_t>(term)] = (positioning ? 0.004 : 0.1 * size) * (0.5 + 0.5 * std::abs(unit(rng)));
    t.period[static_cast<size_t>(term)] = positioning ? 37.0 : 700.0 + 300.0 * unit(rng);
    t.phase[static_cast<size_t>(term)] = kPi * unit(rng);
  }
  for (int w = 18; w < 21; ++w) t.cubic[static_cast<size_t>(w)] = {0.0, 0.0, 0.0};
  // Squareness enters as q * W: keep it in cubic[0] and evaluate with u = 1.
  for (int w = 18; w < 21; ++w) t.cubic[static_cast<size_t>(w)][0] = 2e-5 * unit(rng);
  return t;
}

inline std::vector<Eigen::Vector3d> Mesh(const Eigen::Vector3d& step) {
  std::vector<Eigen::Vector3d> q;
  for (double x = 0; x <= kWorkspace.x() + 1e-9; x += step.x())
    for (double y = 0; y <= kWorkspace.y() + 1e-9; y += step.y())
      for (double z = 0; z <= kWorkspace.z() + 1e-9; z += step.z()) q.emplace_back(x, y, z);
  return q;
}

struct Tracker {
  Eigen::Matrix3d rotation = EulerXyz({63.0, 14.0, 35.0});  // [IJSIMM 2016] Table I, position 4
  Eigen::Vector3d translation{1100.0, -1000.0, 600.0};
};

inline std::vector<Observation> Readings(const Truth& truth, const std::vector<Eigen::Vector3d>& commands, const Tracker& tracker,
                                  const TrackerNoise* noise, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Observation> out;
  for (const Eigen::Vector3d& q : commands) {
    Observation o;
    o.command = q;
    o.measured = SeedReading(truth.At(q), q, tracker.rotation, tracker.translation);
    if (noise != nullptr) {
      // Noise on the tracker's own coordinates, written out here from [IJSIMM 2016] eqs. 22-24.
      const double r = o.measured.norm();
      double az = std::atan2(o.measured.y(), o.measured.x());
      double el = std::asin(o.measured.z() / r);
      const double range = r + (noise->range_sigma_mm + noise->range_sigma_per_mm * r) * normal(rng);
      az += noise->azimuth_sigma_rad * normal(rng);
      el += noise->elevation_sigma_rad * normal(rng);
      o.measured = range * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      o.covariance = noise->Covariance(o.measured);
    }
    out.push_back(o);
  }
  return out;
}

inline ParameterLayout MachineLayout(Basis basis, int order) {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = kTool;
  ParameterLayout layout(chain, {Travel{0, kWorkspace.x()}, Travel{0, kWorkspace.y()}, Travel{0, kWorkspace.z()}});
  for (const char* axis : {"x", "y", "z"}) {
    for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"}) layout.SetTerm(std::string(axis) + kind, basis, order);
  }
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, basis, 0);
  return layout;
}

inline IdentificationOptions Estimated() {
  IdentificationOptions o;
  o.instrument = InstrumentPose::kEstimated;
  o.num_threads = 1;
  return o;
}

}  // namespace fvm::stage::testing
