#pragma once
// How well an aligned pair of crops matches (quality) and how precisely it fixes the shift (information).
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>

#include "imaging/registration_floor.h"
#include "imaging/tile_prefilter.h"

namespace fvm::imaging::detail {

// The floor of a pair's standard uncertainty per direction (MeasureAlignment).
constexpr double kSystematicPx = kRegistrationFloorPx;
// A thin overlap's (narrower than kThinOverlapPx, its crops mirrored out) errors exceed what its noise alone
// explains, by this factor in standard deviation: the crop's edges, where the high-pass and the quadratic meet the
// mirrored context, stay put while the scene moves under them, and blobs cut by them pull the shift. Measured on
// the searched pairs of the sparse synthetic sets (seeds 1-8, 532 directions): the rms of their errors over their
// noise-only claims was 2.24, and did not shrink when the residuals' correlation was counted (a Newey-West sandwich
// with lags up to 64 px: 1.8-1.9), so it is no correlated noise. A floor in quadrature instead (0.065 px) also
// gave 1.0 but weighed the good pairs like the poor ones, and the tiles landed twice as far from the truth.
// (tile_registration_test: SearchedThinPairsClaimHonestUncertainties.)
constexpr double kThinOverlapInflation = 2.24;

// How well an aligned overlap matches, and how precisely it fixes the shift.
struct Alignment {
  double quality = 0.0;
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
};
// `match_sigma` > 0: where the crops' gradients do not stand out of their noise, the information of the crops
// smoothed by a Gaussian of that sigma (px).
Alignment MeasureAlignment(const Prepared& a, const Prepared& b, const Eigen::Vector2d& e, double match_sigma);

}  // namespace fvm::imaging::detail
