#include "artefacts/machine_truth.h"

#include <fmt/core.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fvm::artefacts {

void Workspace::Check() const {
  if (!min.allFinite() || !max.allFinite()) throw std::invalid_argument("workspace limits must be finite numbers (mm)");
  for (int k = 0; k < 3; ++k) {
    if (!(max[k] > min[k])) {
      throw std::invalid_argument(fmt::format("workspace: the travel of {} must have max > min (got {} .. {} mm)",
                                              "xyz"[k], min[k], max[k]));
    }
  }
}

double TermTruth::Value(double u) const {
  double v = poly[0] + u * (poly[1] + u * (poly[2] + u * poly[3]));
  if (sine_pitch_mm > 0.0) v += sine_amplitude * std::sin(2.0 * std::numbers::pi * u / sine_pitch_mm + sine_phase_rad);
  return v;
}

void TermValuesAt(const MachineTruth& truth, const Eigen::Vector3d& q, double e[stage::kNumErrorTerms]) {
  for (int t = 0; t < stage::kNumErrorTerms; ++t) {
    const TermTruth& term = truth.terms[static_cast<size_t>(t)];
    if (stage::GetErrorTerm(t).kind == stage::ErrorKind::kSquareness) {
      e[t] = term.poly[0];  // one angle
      continue;
    }
    const int k = static_cast<int>(stage::GetErrorTerm(t).axis);
    e[t] = term.Value(q[k] - truth.workspace.min[k]);
  }
}

}  // namespace fvm::artefacts
