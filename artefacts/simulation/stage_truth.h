#pragma once
// The stage a simulator measures on: the error model's polynomial part with known coefficients, and a periodic part
// no polynomial model takes exactly, so that a fit to simulated data cannot be exact by construction.

#include <Eigen/Core>
#include <vector>

#include "stage/parameter_layout.h"

namespace fvm::artefacts {

// A lead screw's cyclic error rides on the polynomial part: periodic_um along X as a function of x, and along Y of y,
// with period period_mm.
struct StageTruth {
  stage::ParameterLayout layout;
  std::vector<double> values;  // free coefficients of layout, mm and rad
  double periodic_um = 0.0;
  double period_mm = 25.0;
  Eigen::Vector3d Forward(const Eigen::Vector3d& q) const;  // the part point on the optical axis at command q
  Eigen::Matrix3d Camera(const Eigen::Vector3d& q) const;   // C(q): camera frame to part frame
  // The command whose Forward is `part` (stage::Inverse of the polynomial part, corrected for the periodic one).
  Eigen::Vector3d Inverse(const Eigen::Vector3d& part) const;
};

}  // namespace fvm::artefacts
