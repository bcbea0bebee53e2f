#pragma once
// What the discrepancy workflow says when its last step leaves more than noise (stage/discrepancy.h): whether the
// identification data fit to noise, and if not, what is left and its likeliest cause, one sentence.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "stage/calibration.h"
#include "stage/identification.h"
#include "stage/residual_summary.h"
#include "stage/stitched_frame.h"

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

// A drift in measurement time in place of the held-out placements' turns about their first tiles (frame_rotation):
// along bars measured in order a drift grows from each first tile as a turn's displacement does, and the
// identification's linear terms, which took part of it, err on each held-out bar in proportion to the arm from its
// first tile. When three drift rates and six linear terms of the arm, common to every placement and fitted to the
// held-out residuals of `calibration`, leave no more of them than the turns do (`turned_residuals`: with each
// placement's turn taken out), the turns are no evidence of a turned frame (a turn that differs from placement to
// placement, as the stage's rotation at each first tile does, is not common to them), provided the drift's rates are
// significant beyond the linear terms alone (F-test at `alpha`): the note that says so, and what remains unexplained
// (`validation`, `fit`: the held-out and identification residuals). None when the data carry no times.
struct TurnsRefused {
  std::string note, unexplained;
};
struct TurnTestOutcome {
  int step = 0;
  double p_value = 1.0;
  bool drift_corrected = false;  // a thermal_drift was applied before the turn test
};
std::optional<TurnsRefused> DriftInsteadOfTurns(const Calibration& calibration, const MeasurementSet& validate,
                                                StitchedFrame frame, const std::vector<Eigen::Vector3d>& turned_residuals,
                                                const TurnTestOutcome& turns, const ResidualSummary& validation,
                                                const ResidualSummary& fit, double alpha);

}  // namespace fvm::stage
