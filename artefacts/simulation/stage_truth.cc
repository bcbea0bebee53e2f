#include "artefacts/simulation/stage_truth.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "stage/inverse_model.h"
#include "stage/stitched_frame.h"

namespace fvm::artefacts {
namespace {

Eigen::Vector3d Periodic(const StageTruth& t, const Eigen::Vector3d& q) {
  const double k = 2.0 * std::numbers::pi / t.period_mm;
  // Phases of their own, so that neither cycle is zero at the travel's origin.
  return t.periodic_um * 1e-3 * Eigen::Vector3d(std::sin(k * q.x() + 0.7), std::sin(k * q.y() + 2.1), 0.0);
}

}  // namespace

Eigen::Vector3d StageTruth::Forward(const Eigen::Vector3d& q) const { return stage::Forward(layout, values, q) + Periodic(*this, q); }

Eigen::Matrix3d StageTruth::Camera(const Eigen::Vector3d& q) const {
  return stage::CameraOrientation(layout, values.data(), q);
}

Eigen::Vector3d StageTruth::Inverse(const Eigen::Vector3d& part) const {
  // The periodic part moves the command by its amplitude (a micrometre) and changes by 1e-4 of it across that:
  // three passes of the polynomial inverse settle it far below a nanometre.
  Eigen::Vector3d q = part;
  for (int pass = 0; pass < 3; ++pass) {
    const stage::InverseResult r = stage::Inverse(layout, values.data(), part - Periodic(*this, q));
    if (!r.converged) throw std::runtime_error("simulation: the stage model could not be inverted");
    q = r.command;
    if (periodic_um == 0.0) break;
  }
  return q;
}

}  // namespace fvm::artefacts
