#pragma once
// The published YXFZ stage model written out from [Pérez 2019], independently of the library (eqs. 1-5;
// section 2.1): the truth that stage tests make their data with, so that a mistake in the library's chain,
// inverse or first tile cannot cancel between the simulator and the identification ("inverse crime").
//
//   TP = RX^-1 [ RY^-1 (TL - TY) - TX ],  TX = (-x + xTx, xTy - x xWy, xTz - x xWz),
//   TY = (yTx, -y + yTy, yTz - y yWz),     TL = (0, 0, z),  Rk = [1 -kRz kRy; kRz 1 -kRx; -kRy kRx 1].

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "stage/identification.h"

namespace fvm::stage::testing {

// The 15 published error functions at one stage position.
struct PublishedErrors {
  double xTx, xTy, xTz, yTx, yTy, yTz, xRx, xRy, xRz, yRx, yRy, yRz, xWy, xWz, yWz;
};

inline Eigen::Matrix3d PublishedRotation(double rx, double ry, double rz) {  // eq. 2
  Eigen::Matrix3d r;
  r << 1, -rz, ry, rz, 1, -rx, -ry, rx, 1;
  return r;
}

// Eqs. 1-5 written out literally.
inline Eigen::Vector3d PublishedEquation1(const PublishedErrors& e, const Eigen::Vector3d& q) {
  const double x = q.x(), y = q.y(), z = q.z();
  const Eigen::Vector3d tx(-x + e.xTx, e.xTy - x * e.xWy, e.xTz - x * e.xWz);
  const Eigen::Vector3d ty(e.yTx, -y + e.yTy, e.yTz - y * e.yWz);
  const Eigen::Vector3d tl(0, 0, z);
  const Eigen::Matrix3d rx = PublishedRotation(e.xRx, e.xRy, e.xRz);
  const Eigen::Matrix3d ry = PublishedRotation(e.yRx, e.yRy, e.yRz);
  return rx.inverse() * (ry.inverse() * (tl - ty) - tx);
}

// A stage whose error functions are straight lines in their axis' coordinate plus, where `ripple_mm` > 0, a
// sine on every translation (a lead-screw period the polynomial models cannot take): the truth identification
// tests fit, drawn with a fixed seed. Magnitudes as in [Pérez 2019]: translations up to ~100 um over the
// travel, rotations and squareness of ~1e-4 rad.
struct PublishedStage {
  // Per term: value at 0 and slope per 100 mm of its axis, in the order xT(x,y,z) xR(x,y,z) yT(x,y,z) yR(x,y,z)
  // W(xy,xz,yz); the squareness terms are constants.
  std::array<double, 15> offset{}, slope{};
  double ripple_mm = 0.0;
  double ripple_period_mm = 37.0;
  double bend_mm = 0.0;  // xTx gains bend_mm (x / 100 mm)^2: a second order the 27 model lacks

  // `rotation_size`: offsets and slopes of the rotation terms (rad); squareness keeps 2e-4.
  static PublishedStage Draw(unsigned seed, double ripple_mm = 0.0, double rotation_size = 2e-4) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    PublishedStage s;
    s.ripple_mm = ripple_mm;
    for (int k = 0; k < 15; ++k) {
      const bool translation = k < 12 && k % 6 < 3;
      const bool rotation = k < 12 && k % 6 >= 3;
      const double size = translation ? 0.04 : rotation ? rotation_size : 2e-4;  // mm; rad
      s.offset[static_cast<size_t>(k)] = size * unit(rng);
      s.slope[static_cast<size_t>(k)] = k < 12 ? size * unit(rng) : 0.0;
    }
    return s;
  }

  PublishedErrors ErrorsAt(double x, double y) const {
    std::array<double, 15> v{};
    for (int k = 0; k < 15; ++k) {
      const double along = k < 6 ? x : y;  // x's terms follow x, y's follow y
      v[static_cast<size_t>(k)] = offset[static_cast<size_t>(k)] + (k < 12 ? slope[static_cast<size_t>(k)] * along / 100.0 : 0.0);
    }
    PublishedErrors e{};
    const auto wave = [&](double t, double phase) {
      return ripple_mm * std::sin(2 * std::numbers::pi * t / ripple_period_mm + phase);
    };
    e.xTx = v[0] + wave(x, 0.3) + bend_mm * (x / 100.0) * (x / 100.0), e.xTy = v[1] + wave(x, 1.1), e.xTz = v[2] + wave(x, 2.0);
    e.xRx = v[3], e.xRy = v[4], e.xRz = v[5];
    e.yTx = v[6] + wave(y, 0.7), e.yTy = v[7] + wave(y, 1.9), e.yTz = v[8] + wave(y, 2.6);
    e.yRx = v[9], e.yRy = v[10], e.yRz = v[11];
    e.xWy = v[12], e.xWz = v[13], e.yWz = v[14];
    return e;
  }

  // Part coordinates of the commanded point q.
  Eigen::Vector3d Part(const Eigen::Vector3d& q) const { return PublishedEquation1(ErrorsAt(q.x(), q.y()), q); }

  // How the camera turns a vector of its own frame into the part frame's, inverted: R_Y R_X at q (eq. 1 maps a
  // tool offset v to R_X^-1 R_Y^-1 v).
  Eigen::Matrix3d CameraToStitched(const Eigen::Vector3d& q) const {
    const PublishedErrors e = ErrorsAt(q.x(), q.y());
    return PublishedRotation(e.yRx, e.yRy, e.yRz) * PublishedRotation(e.xRx, e.xRy, e.xRz);
  }
};

// The first tile of a measurement ([Pérez thesis] 5.7.2), written out: lowest x, highest y of the positions, at the
// height of the position nearest that corner.
inline Eigen::Vector3d PublishedFirstTile(const std::vector<Eigen::Vector3d>& positions) {
  Eigen::Vector2d corner(positions[0].x(), positions[0].y());
  for (const Eigen::Vector3d& p : positions) corner = {std::min(corner.x(), p.x()), std::max(corner.y(), p.y())};
  double best = INFINITY, z = 0.0;
  for (const Eigen::Vector3d& p : positions) {
    const double d = (p.head<2>() - corner).norm();
    if (d < best) best = d, z = p.z();
  }
  return {corner.x(), corner.y(), z};
}

// A bar of 17 calottes at 10 mm pitch laid on the stage from `start` in direction `angle_rad`, slightly tilted
// (it never lies flat: +-1.5 mrad along it, as in [Pérez 2019]'s set-up) at z = -50 mm: the commanded centres.
inline std::vector<Eigen::Vector3d> BarPlacement(const Eigen::Vector2d& start, double angle_rad, double tilt) {
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < 17; ++i) {
    const double along = 10.0 * i;
    q.emplace_back(start.x() + std::cos(angle_rad) * along, start.y() + std::sin(angle_rad) * along, -50.0 + tilt * along);
  }
  return q;
}

struct PublishedMeasurements {
  MeasurementSet identify, validate;
};

// Effects beyond the stage model, written out here for the discrepancy workflow's tests: a scale of the stitched xy
// distances about the first tile (a lens scale error), a drift of the stitching-free centres with measurement time
// (20 s a calotte, from the start of each placement), and blunders (failed sphere fits) on stitching-free centres
// of the second identification placement.
struct PublishedEffects {
  double scale = 0.0;
  Eigen::Vector3d drift_mm_per_s = Eigen::Vector3d::Zero();
  int blunders = 0;
  double blunder_mm = 0.08;
  // The identification bars lie on wedges rising by -rise, 0, +rise over their length (mm): measured in order,
  // their height grows with time along each, so a drift and pitch and roll look alike.
  double rise_mm = 0.0;
};

// The three identification placements of [Pérez 2019] (along x, along y, oblique, from the corner at lowest x and
// highest y) and `validation` random placements, measured on `stage`: the stitching-free centre is the command
// plus noise, the stitched one the part coordinates (eq. 1) relative to the measurement's first tile, plus noise
// (`noise_mm` per coordinate in both). `apart`: the identification placements start up to 30 mm apart.
// `turned`: the stitched export keeps the orientation the camera had at the first tile a, as an instrument that
// registers tiles by translation does: s = a + R_Y R_X (at a) (P(q) - P(a)); otherwise s = a + P(q) - P(a).
inline PublishedMeasurements MeasureOnPublishedStage(const PublishedStage& stage, unsigned seed, double noise_mm,
                                                      int validation = 10, bool apart = false, bool turned = false,
                                                      const PublishedEffects& effects = {}) {
  std::mt19937_64 rng(seed * 7919u + 1u);
  std::mt19937_64 blunder_rng(seed * 104729u + 7u);  // its own draws: without blunders, the same data as before
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> tilt(-1.5e-3, 1.5e-3), shift(0.0, 30.0), angle(-std::numbers::pi, std::numbers::pi),
      coordinate(-195.0, -5.0);
  const auto noisy = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(v.x() + noise_mm * noise(rng), v.y() + noise_mm * noise(rng), v.z() + noise_mm * noise(rng));
  };
  PublishedMeasurements out;
  const auto measure = [&](MeasurementSet& set, const std::vector<Eigen::Vector3d>& commands) {
    const int group = static_cast<int>(set.anchors.size());
    const Eigen::Vector3d anchor = PublishedFirstTile(commands);
    // The stitched coordinates start at the first tile, where the stage's own error is not seen.
    const Eigen::Matrix3d turn = turned ? stage.CameraToStitched(anchor) : Eigen::Matrix3d::Identity();
    std::vector<Eigen::Vector3d> free;
    for (size_t i = 0; i < commands.size(); ++i) {
      const Eigen::Vector3d& q = commands[i];
      const double t = 20.0 * static_cast<double>(i);
      free.push_back(noisy(q) + effects.drift_mm_per_s * t);
      Eigen::Vector3d stitched = turn * (stage.Part(q) - stage.Part(anchor));
      stitched.head<2>() *= 1.0 + effects.scale;
      Observation o;
      o.command = free.back();
      o.measured = noisy(anchor + stitched);
      o.group = group;
      set.observations.push_back(o);
      set.t_s.push_back(t);
    }
    if (&set == &out.identify && group == 1 && effects.blunders > 0) {
      std::vector<size_t> order(commands.size());
      std::iota(order.begin(), order.end(), size_t{0});
      std::shuffle(order.begin(), order.end(), blunder_rng);
      std::normal_distribution<double> direction(0.0, 1.0);
      const size_t first = set.observations.size() - commands.size();
      for (int k = 0; k < effects.blunders; ++k) {
        const Eigen::Vector3d d(direction(blunder_rng), direction(blunder_rng), direction(blunder_rng));
        set.observations[first + order[static_cast<size_t>(k)]].command += effects.blunder_mm * d.normalized();
      }
    }
    set.anchors.push_back(PublishedFirstTile(free));
    set.groups.push_back("placement " + std::to_string(group));
  };
  const Eigen::Vector2d corner(-185.0, -15.0);
  for (const double a : {0.0, -std::numbers::pi / 2, -std::numbers::pi / 4}) {
    const Eigen::Vector2d start = apart ? Eigen::Vector2d(corner + Eigen::Vector2d(shift(rng), -shift(rng))) : corner;
    const double wedge = effects.rise_mm * (static_cast<double>(out.identify.anchors.size()) - 1.0) / 160.0;
    measure(out.identify, BarPlacement(start, a, tilt(rng) + wedge));
  }
  while (static_cast<int>(out.validate.anchors.size()) < validation) {
    const Eigen::Vector2d start(coordinate(rng), coordinate(rng));
    const double a = angle(rng);
    const Eigen::Vector2d end = start + 160.0 * Eigen::Vector2d(std::cos(a), std::sin(a));
    if (end.x() < -200.0 || end.x() > 0.0 || end.y() < -200.0 || end.y() > 0.0) continue;  // off the travel
    measure(out.validate, BarPlacement(start, a, tilt(rng)));
  }
  return out;
}

}  // namespace fvm::stage::testing
