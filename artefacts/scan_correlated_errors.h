#pragma once
// What the displacements of a scan share, which white registration noise does not model, and what it does to the
// coefficients of a calibration from scans (issue 31). Two errors do not average out along a scan:
//
// - The registrations' sub-pixel bias. Interpolation-based matching pulls a sub-pixel shift towards whole pixels
//   ("pixel locking", [Shimizu 2005]; for image correlation with interpolated intensities [Schreier 2000]): the
//   error is a periodic function of the fractional shift f, about -k sin(2 pi f) / (2 pi) px. Along a scan every
//   step has nearly the same fractional shift, and with a whole number of pixels commanded per step the fractional
//   shift is the stage's own error per step: the bias is a gain on the stage's error that every pair of every scan
//   shares, which the scans cannot tell from the stage (they do not disagree about it). Chained along 70 tiles, a
//   gain of 1 % on a stage error of tens of micrometres is half a micrometre. Its size on a given texture is not
//   known, so k_x and k_y (one for all pairs each) are carried with the standard uncertainty kSubpixelGainU.
// - What the model cannot take (a lead screw's cycle). The fit takes the part of it that looks like the model's
//   terms, and that part is in no residual. The misfit is taken as a stationary process along each scan of the
//   character its residuals show: each scan's residuals shifted circularly by every lag stand for misfits that
//   could as well have been, and the spread of the coefficients' response to them is the misfit's share.
//
// Both propagate through the fit linearised: the coefficients move by (J^T W J)^-1 J^T W e for displacement errors
// e, J the displacements' Jacobian (their turn, tens of microradians, left out), W the registrations' information
// (z only where height-map tiles gave a pair its height step).

#include <Eigen/Core>
#include <vector>

#include "stage/calibration.h"
#include "stage/identification.h"

namespace fvm::artefacts {

// k's standard uncertainty, a Type B figure of the registration (imaging/subpixel_refinement.h): the gain fitted
// to the registrations' errors against the truth of rendered scans (ground texture to 0.25 cycles/px, 256 px tiles,
// seeds 1-8 of the scan simulator) is 0.002-0.022 in x and 0.013-0.020 in y, 0.014 rms over the 16.
constexpr double kSubpixelGainU = 0.014;

// The coefficients' covariance from each of the two.
struct ScanCorrelatedErrors {
  Eigen::MatrixXd subpixel_bias;
  Eigen::MatrixXd misfit;
};

// `set`: displacement observations (ScanDisplacements: measured (o_x p, -o_y p) from the registered offset o px and
// the pixel size p), one group per scan, in scan order; `residuals`: what the fit left of them (stage::Identify).
ScanCorrelatedErrors ScanCorrelatedErrorCovariances(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                                    const std::vector<Eigen::Vector3d>& residuals, double pixel_mm,
                                                    double gain_u = kSubpixelGainU);

// The objective's field distortion, identified from the overlaps and taken out of every pair's offset
// (workflows/scan_distortion.h): an error dc of its coefficients moves displacement i by S_i dc, every pair at once,
// so the coefficients' covariance gains R C R^T, R = (J^T W J)^-1 sum_i J_i^T W_i S_i, C the field's covariance.
// `sensitivity_mm`: S_i in mm per px of coefficient (3 x K, z row 0), one per observation of `set`.
Eigen::MatrixXd FieldDistortionCovariance(const stage::Calibration& calibration, const stage::MeasurementSet& set,
                                          const std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>& sensitivity_mm,
                                          const Eigen::MatrixXd& field_covariance_px2);

}  // namespace fvm::artefacts
