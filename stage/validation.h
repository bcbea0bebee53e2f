#pragma once
// How well a calibration predicts measurements it was not fitted to.
//
// Every validation measurement is referenced to its own first tile (the instrument anchors each stitched
// measurement there, 000:4826), so the residual is F(q) - F(a) + a - s whatever anchoring identification used:
// a constant offset common to a measurement is not a stage error the calibration can be blamed for.

#include <Eigen/Core>
#include <vector>

#include "stage/calibration.h"
#include "stage/identification.h"

namespace fvm::stage {

// Count, mean, rms, largest and smallest of Euclidean residuals: the statistics every report of fvm quotes.
struct ResidualSummary {
  int count = 0;
  double mean_mm = 0, rms_mm = 0, max_mm = 0, min_mm = 0;
};
ResidualSummary Summarize(const std::vector<Eigen::Vector3d>& residuals);

struct ValidationStats : ResidualSummary {
  double predicted_rms_mm = 0;  // what the calibration's covariance and noise predict for rms_mm
  std::vector<Eigen::Vector3d> residuals;
};

// `anchors[g]` is the first tile of observation group g; without anchors (data not referenced to a first tile,
// such as laser-tracker readings) the residual is F(q) - s. A null calibration means "no compensation".
ValidationStats Validate(const Calibration* calibration, const std::vector<Observation>& observations,
                         const std::vector<Eigen::Vector3d>& anchors);

// Errors of the distances from the first observation of each group to every other one (compensated free
// distance - stitched distance), mm: anchor-free, the paper's figure of merit (Figs. 6 and 8).
std::vector<double> DistanceErrors(const Calibration* calibration, const std::vector<Observation>& observations);

}  // namespace fvm::stage
