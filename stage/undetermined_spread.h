#pragma once
// What the coefficients identification fixed at zero still do where it did not measure (issue 31). Their true values
// are not zero: pitch and roll on a nearly flat bar act through the tilt and the lever arms of every other
// placement, and the free coefficients' covariance cannot say so. Without a truth to go by, each gets the mean square
// of the determined coefficients of its kind (translation, rotation, squareness) and power as its variance:
// empirical Bayes, as large as its determined kin. On the identification data the free coefficients took part of it
// up (Calibration::undetermined); elsewhere, what is left acts: its effect less the free coefficients' answer to it.

#include <Eigen/Core>
#include <optional>

#include "stage/calibration.h"

namespace fvm::stage {

// The prior variance of each of calibration.undetermined.names (mm^2, rad^2); 0 where no coefficient of its kind and
// power was determined.
Eigen::VectorXd UndeterminedPrior(const Calibration& calibration);

// The calibration with its undetermined coefficients set free at their fixed values, and as covariance the spread
// they add to the calibration's own: E diag(prior) E^T with E = (absorbed; -1), the free coefficients' error and
// theirs per unit of each. Propagated with this calibration's Jacobians (J Cov J^T), it is their share of any
// prediction. nullopt where identification fixed nothing, or did not say (a calibration read from a file).
std::optional<Calibration> UndeterminedSpread(const Calibration& calibration);

}  // namespace fvm::stage
