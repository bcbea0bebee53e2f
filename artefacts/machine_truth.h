#pragma once
// A machine tool's axes and its true geometric errors: the travel of the three axes (what the error functions of a
// verification are defined on, real data or simulated) and the 21 error terms of a machine whose errors are known
// (the simulator's truth, its truth.json, and --errors files: artefacts/io/machine_truth_file.h).

#include <Eigen/Core>
#include <array>

#include "stage/error_terms.h"

namespace fvm::artefacts {

// The travel of the three axes (mm): axis k runs from min[k] (its origin, where every error term is zero) to max[k].
struct Workspace {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d(2500.0, 1500.0, 1200.0);
  void Check() const;  // throws std::invalid_argument unless min < max on each axis, all finite
};

// One geometric error term as a function of its axis coordinate q, with u = q - origin (mm):
//   value(u) = poly[0] + poly[1] u + poly[2] u^2 + poly[3] u^3 + sine_amplitude sin(2 pi u / sine_pitch_mm + sine_phase_rad)
// in mm (translation terms) or rad (rotation and squareness terms). sine_pitch_mm 0: no sine. A squareness term
// is one angle: poly[0] only.
struct TermTruth {
  std::array<double, 4> poly{};
  double sine_amplitude = 0.0;
  double sine_pitch_mm = 0.0;
  double sine_phase_rad = 0.0;
  double Value(double u) const;
};

// The machine's true errors: the 21 terms of stage/error_terms.h, each over the travel of its own axis
// (u = q_k - workspace.min[k]). Random truths vanish at each axis' origin (poly[0] = -A sin(phase)); the effect of
// a squareness term, -q W, vanishes there when the origin is 0.
struct MachineTruth {
  Workspace workspace;
  std::array<TermTruth, stage::kNumErrorTerms> terms{};
};

// The values e[0..20] of the 21 terms at command q (what stage::ChainForward takes).
void TermValuesAt(const MachineTruth& truth, const Eigen::Vector3d& q, double e[stage::kNumErrorTerms]);

}  // namespace fvm::artefacts
