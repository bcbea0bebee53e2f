#pragma once
// What a metrologist would look at first in an identification's residuals: their correlation with position,
// height, time and calotte index; per-placement offsets; the largest standardised residual.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "stage/identification.h"

namespace fvm::stage {

// Up to five findings, the strongest first; "no structure: ..." when there is none. `sigma`: noise per coordinate.
std::vector<std::string> Findings(const std::vector<Eigen::Vector3d>& residuals, const MeasurementSet& set, double sigma);

}  // namespace fvm::stage
