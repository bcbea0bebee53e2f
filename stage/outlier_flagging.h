#pragma once
// Blunders among an identification's centres (failed sphere fits): improbable for Gaussian noise of a robust scale
// and as improbable against their neighbours along the bar, found one at a time with a refit between.

#include <Eigen/Core>
#include <vector>

#include "stage/identification.h"
#include "stage/parameter_layout.h"

namespace fvm::stage {

// Noise per coordinate that a few blunders cannot inflate: the median absolute residual (MAD) scaled to sigma.
double RobustSigma(const std::vector<Eigen::Vector3d>& residuals, double floor_mm);

// Centres whose error is improbable for Gaussian noise of the robust scale (Bonferroni [Dunn 1961] over the centres),
// and as improbable against their neighbours', found one at a time: the worst is taken out and `layout` refitted
// (with `anchor` and the set's anchors) before the next is judged, so that a large blunder, which drags the fit
// towards itself, cannot make its good neighbours look bad. `residuals`: the fit's to `identify`. Indices into it.
std::vector<int> FlagOutliers(const ParameterLayout& layout, const MeasurementSet& identify, Anchor anchor,
                              const std::vector<Eigen::Vector3d>& residuals, const IdentificationOptions& base_options,
                              double alpha);

}  // namespace fvm::stage
