#pragma once
// What the discrepancy workflow says when its last step leaves more than noise (stage/discrepancy.h): whether the
// identification data fit to noise, and if not, what is left and its likeliest cause, one sentence.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/residual_summary.h"

namespace fvm::stage {

struct Remainder {
  bool fits_noise = true;   // the held-out turn test may run
  std::string unexplained;  // "unexplained: ..."; empty when nothing is to be said
};

// The identification data do not fit to noise while a candidate the held-out placements refused at the last step
// (`refused_now`, best first) still explains part of them significantly, nor while their rms per coordinate
// (`num_free` coefficients fitted) stays above twice the noise between neighbouring calottes (NeighbourNoise:
// no smooth pattern reaches it, so twice that is far beyond chance for a batch's 100+ equations). After any
// refusal (`ever_refused`) the turn test does not run either: a drift left on placements measured in order grows
// perpendicular to each bar like a turn; then, when the held-out placements (`validation`) keep more than twice the
// identification's mean residual, that is said instead.
Remainder JudgeRemainder(const std::vector<Eigen::Vector3d>& residuals, int num_free, const MeasurementSet& identify,
                         const std::vector<std::string>& refused_now, const std::vector<std::string>& ever_refused,
                         const ResidualSummary& validation);

}  // namespace fvm::stage
