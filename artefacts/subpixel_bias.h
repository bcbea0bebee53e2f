#pragma once
// The registrations' sub-pixel bias and what it does to a calibration from scans (issue 31). Interpolation-based
// matching pulls a sub-pixel shift towards whole pixels ("pixel locking", [Shimizu 2005]; for Lanczos and
// splines in image correlation [Schreier 2000]): the error is a periodic function of the fractional shift f,
// about -k sin(2 pi f) / (2 pi) px. Along a scan every step has nearly the same fractional shift, and with a whole
// number of pixels commanded per step the fractional shift is the stage's own error per step: the bias is then a
// gain on the stage's error that every pair of every scan shares, which no scan can tell from the stage (scans do
// not disagree about it) and which white registration noise does not model. Chained along 70 tiles, a gain of 1 %
// on a stage error of tens of micrometres is half a micrometre.
//
// Its size is not known on a given texture, so it is carried as an uncertainty: k_x and k_y, one for all pairs
// each, of standard uncertainty kSubpixelGainU, propagated to the coefficients through the fit's linear map.

#include <Eigen/Core>

#include "stage/calibration.h"
#include "stage/identification.h"

namespace fvm::artefacts {

// k's standard uncertainty, a Type B figure of the registration (imaging/subpixel_refinement.h): the gain fitted
// to the registrations' errors against the truth of rendered scans (ground texture to 0.25 cycles/px, 256 px tiles,
// seeds 1-8 of the scan simulator) is 0.002-0.022 in x and 0.013-0.020 in y, 0.014 rms over the 16.
constexpr double kSubpixelGainU = 0.014;

// The coefficients' covariance from the sub-pixel gain's uncertainty `gain_u`, for displacement observations
// (ScanDisplacements: measured (o_x p, -o_y p) from the registered offset o px and the pixel size p).
Eigen::MatrixXd SubpixelBiasCovariance(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                       double pixel_mm, double gain_u = kSubpixelGainU);

}  // namespace fvm::artefacts
