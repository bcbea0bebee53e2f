#pragma once
// How well an aligned pair of crops matches (quality) and how precisely it fixes the shift (information).
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>

#include "imaging/tile_prefilter.h"

namespace fvm::imaging::detail {

// The floor of a pair's standard uncertainty per direction (MeasureAlignment).
constexpr double kSystematicPx = 0.005;

// How well an aligned overlap matches, and how precisely it fixes the shift.
struct Alignment {
  double quality = 0.0;
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
};
// `match_sigma` > 0: where the crops' gradients do not stand out of their noise, the information of the crops
// smoothed by a Gaussian of that sigma (px).
Alignment MeasureAlignment(const Prepared& a, const Prepared& b, const Eigen::Vector2d& e, double match_sigma);

}  // namespace fvm::imaging::detail
