#pragma once
// The registrations of stitched calibration scans as observations of the stage (issue 21): the same estimator as
// an artefact batch's pairs, with a tile where a batch has a calotte. A stitched scan is the chain of registrations
// from its first tile; its stitching-free coordinates are the encoder readings.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "imaging/tile_registration.h"
#include "stage/identification.h"

namespace fvm::artefacts {

struct RegisteredScan {
  std::string name;
  std::vector<Eigen::Vector3d> encoder_mm;  // tile centres, scan order
  imaging::ChainRegistration registration;
  // Height-map tiles (heights in mm of the part relative to each tile's focal plane): the z step of each pair, how
  // far the stage rose from a to b, imaging::OverlapHeightStep(a, b, offset); empty for grey tiles, which show no
  // height.
  std::vector<imaging::HeightStep> height_steps;
  // Tiles undistorted by an objective's field identified from the overlaps (workflows/scan_distortion.h): how each
  // pair's offset moves with the field's coefficients (px per px of coefficient, 2 x K; one per pair, empty without a
  // field) and the coefficients' covariance (px^2). An error of the field moves every pair of every scan at once,
  // which no pair's own covariance holds: IdentifyFromScans adds its share to the calibration's covariance.
  std::vector<Eigen::Matrix<double, 2, Eigen::Dynamic>> field_sensitivity;
  Eigen::MatrixXd field_covariance_px2;
};

// A scan's tiles registered as a chain from where the encoders say they are (the stage's mm turned into pixels,
// x right and y down, from the first tile); height-map tiles (`height_maps`) also give each registered pair's z
// step from the overlap. `on_pair` is called as each pair is registered (progress).
RegisteredScan RegisterScan(std::string name, std::vector<Eigen::Vector3d> encoder_mm,
                            const std::vector<imaging::TileImage>& tiles, double pixel_mm, bool height_maps,
                            const imaging::RegistrationOptions& options = {},
                            const std::function<void(int done, int total)>& on_pair = {});
// The offsets the encoders command from the first tile, in pixels (x right, y down).
std::vector<Eigen::Vector2d> NominalOffsetsPx(const std::vector<Eigen::Vector3d>& encoder_mm, double pixel_mm);

// One displacement observation per accepted pair of neighbours (Observation::from = the earlier tile's encoder
// reading, command = the later one's): measured (o_x p, -o_y p) from the registered offset o (px, y down) and the
// pixel size p, weighted by the pair's own information (px^-2, so p^2 times its inverse, y flipped). The
// registrations of a chain are independent pair by pair, where the positions chained from them are not. z is the
// pair's height step where the scan has them, else not observed (grey tiles). One group per scan, anchored at its
// first tile: the first scan's is the frame reference. Throws std::invalid_argument naming two scans that are one
// (the same encoder readings and registrations): given twice, a scan would shrink every uncertainty by sqrt(2).
stage::MeasurementSet ScanDisplacements(const std::vector<RegisteredScan>& scans, double pixel_mm);

// The same registrations as the chained positions a stitched export holds, e_0 + p (position_k - position_0), each
// taken as an independent point of equal weight: what fitting the scan like an artefact batch would do, without the
// correlation along the chain. Only to show what the correlation changes.
stage::MeasurementSet ScanPositions(const std::vector<RegisteredScan>& scans, double pixel_mm);

// Whether displacement i continues the run of consecutive pairs of displacement i - 1: the same scan, starting
// where that one ended (a rejected pair ends a run).
bool ContinuesRun(const stage::MeasurementSet& set, size_t i);

// What a fit to ScanDisplacements leaves, told apart by how it behaves along each chain. Registration noise is
// independent pair to pair; what the model cannot take (a lead screw's cycle, a higher order) changes smoothly from
// pair to pair and does not random-walk when the displacements are chained. Scaling the coefficients' covariance by
// all of the residual, as a fit to independent points does, would treat the smooth part as noise that accumulates
// along 70 tiles, and claim ten times the error the calibration has.
struct ScanResidualSplit {
  // The white part against the registrations' own covariances, from the second differences of consecutive
  // whitened residuals (1: as the registrations say). What scales the covariance.
  double white_ratio = 0.0;
  // The smooth part: the residuals chained into positions along each scan about each run's mean. A stage's error is
  // each axis' error function of its own coordinate (VDI 2617), so a scan along X sees only X's misfit, one along Y
  // only Y's, and a diagonal both; a point between the scans carries X's at its x and Y's at its y. Per coordinate
  // (mm): the standard deviation of the misfit a point inherits, the mean squares of the scans that move each axis
  // (least squares over the scans, a diagonal counting for both) summed over the axes. Pooling every scan's
  // points instead counts a point's misfit as one axis' on a row and a column (sqrt(2) short).
  Eigen::Vector2d misfit_at_point_mm = Eigen::Vector2d::Zero();
  // Its norm (xy, mm): what a prediction between the scans adds to the covariance's share.
  double misfit_mm = 0.0;
};
ScanResidualSplit SplitScanResiduals(const stage::MeasurementSet& set, const std::vector<Eigen::Vector3d>& residuals);

// The stage model from the scans' displacements, one estimator with the artefact batch's (stage::Identify with
// `options`, whose frame and first anchor the scans' set supplies): the coefficients' covariance scaled by the
// residuals' white part instead of all of them, widened by what the pairs of a scan share (the registrations'
// sub-pixel bias, the misfit the coefficients took up: scan_correlated_errors.h), and, with a pixel size
// uncertainty, by the fit's sensitivity to the pixel size (one refit at p + u: the fit is linear in the scale of its
// data).
struct ScanCalibration {
  stage::IdentificationResult result;
  ScanResidualSplit split;
  stage::MeasurementSet set;  // the displacements fitted
};
ScanCalibration IdentifyFromScans(const stage::ParameterLayout& layout, const std::vector<RegisteredScan>& scans,
                                  double pixel_mm, double pixel_u_mm, stage::IdentificationOptions options);

}  // namespace fvm::artefacts
