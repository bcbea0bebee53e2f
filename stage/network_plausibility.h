#pragma once
// Plausibility of a multilateration: whether the ranges can come from trackers at these stations.
//
// A multilateration always returns points, and their a priori uncertainties come from the noise model alone: four
// ranges of 1 m to stations kilometres apart give "points" with micrometre uncertainties although no sphere meets
// another. The residuals say it: measured against the noise model (range sigma a + b * range), a consistent network
// leaves residuals of about one sigma, a wrong file leaves thousands. And a self-calibration can shrink the whole
// network onto one spot when the ranges are (nearly) zero: converged, consistent, and no network at all.

#include <string>

#include "stage/multilateration.h"

namespace fvm::stage {

// Residuals beyond this many range sigmas (rms over the readings) are not noise: the readings are refused.
inline constexpr double kMaxRangeRmsSigmas = 1000.0;
// Self-calibrated stations closer than this many range sigmas (at range zero) are one spot, not a network.
inline constexpr double kMinStationSeparationSigmas = 1000.0;

// Throws ImplausibleFit (stage/plausibility.h) naming the worst reading (point, station, residual in mm and in
// sigmas) when the range residuals' rms exceeds kMaxRangeRmsSigmas, or naming two stations a self-calibration put
// closer than kMinStationSeparationSigmas. `result` is Multilaterate's, with its range residuals.
// Before a self-calibration: throws ImplausibleFit when even the longest range is shorter than
// kMinStationSeparationSigmas range sigmas, so that the stations could only sit on one spot (ranges in the wrong
// units, a zero column).
void CheckRangesSpanANetwork(const MultilaterationProblem& problem, const MultilaterationOptions& options);

void CheckNetworkPlausible(const MultilaterationProblem& problem, const MultilaterationOptions& options,
                           const MultilaterationResult& result);

}  // namespace fvm::stage
