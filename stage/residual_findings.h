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

// The noise per coordinate (mm) the residuals show between neighbouring calottes of one placement, whatever
// shape they follow along it: second differences along each placement, r(i+1) - 2 r(i) + r(i-1), remove any
// pattern that is straight over three neighbours (a drift, a model's missing low-order terms) and leave noise of
// variance 6 sigma^2; robust (median of |d|). Placements with fewer than three observations add nothing; 0 when
// none has three.
double NeighbourNoise(const std::vector<Eigen::Vector3d>& residuals, const MeasurementSet& set);

}  // namespace fvm::stage
