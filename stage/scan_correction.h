#pragma once
// Correcting the points of a stitching-free scan (a point cloud, the grid points of a height map) with an
// identified stage model: every point is moved by the model at its own stage coordinates, through the same
// functions that correct a centre export (Correct, FirstTileCompensation), so a point's result is the centre
// correction of its coordinates, bit for bit.
//
// A scan's coordinates may sit at an offset from the stage's (an export whose origin is the dataset corner): its
// stage coordinates are file + origin. Results come back in the file's frame (corrected stage point - origin), so
// that the corrected scan overlays the input; with a zero origin the two frames are one.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <vector>

#include "stage/calibration.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

struct ScanCorrectionOptions {
  // Unset: the model's part frame (fvm correct --frame stage). Set: the frame a stitched measurement of the same
  // scan started at its first tile would have (--frame first-tile), rotated or translated.
  std::optional<StitchedFrame> first_tile_frame;
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();  // stage position of the file's coordinate origin
};

// Indices of the valid (finite) points whose stage coordinates (point + origin) lie outside the travel the model
// was identified on, along an axis that has error terms (x and y for the microscope: its z errors are neglected).
std::vector<std::size_t> PointsOutsideTravel(const ParameterLayout& layout, const std::vector<Eigen::Vector3d>& points,
                                             const Eigen::Vector3d& origin_mm);

class ScanCorrector {
 public:
  // `stage_points` decides the first tile (FirstTile of the valid ones, in stage coordinates) for the first-tile
  // frame; ignored in the stage frame. Throws InputError when the first-tile frame has no valid point to start at.
  ScanCorrector(const Calibration& calibration, const ScanCorrectionOptions& options,
                const std::vector<Eigen::Vector3d>& file_points);

  // The corrected point in the file's frame, with the covariance the model's coefficients and its unmodelled part give it.
  CorrectedPoint Correct(const Eigen::Vector3d& file_point) const;
  // The same position, without the covariance (several times faster).
  Eigen::Vector3d Position(const Eigen::Vector3d& file_point) const;
  // The rigid shift a whole tile at stage position `tile_centre` (file frame) gets: Position(c) - c.
  Eigen::Vector3d Shift(const Eigen::Vector3d& tile_centre) const { return Position(tile_centre) - tile_centre; }

  const std::optional<FirstTileCompensation>& first_tile() const { return first_tile_; }
  const ScanCorrectionOptions& options() const { return options_; }

 private:
  const Calibration& calibration_;
  ScanCorrectionOptions options_;
  std::optional<FirstTileCompensation> first_tile_;
  // Every coefficient's value, free and fixed, expanded once: the stage frame evaluates the model per point
  // without expanding it again (the same arithmetic as Forward and ForwardJacobian, so the same bits).
  std::vector<double> all_;
};

struct ScanCorrectionSummary {
  std::size_t corrected = 0;        // valid points moved
  std::size_t invalid = 0;          // NaN or infinite points, left as they are and counted
  double largest_shift_mm = 0.0;    // over the corrected points
};

// Corrects `points` (file frame) in place, in parallel over `threads` (0: all cores); invalid points stay as
// they are. With `u`, it is resized to the points and holds each point's standard uncertainties (sqrt of the diagonal
// of its covariance, mm), NaN for invalid points.
ScanCorrectionSummary CorrectScanInPlace(const ScanCorrector& corrector, std::vector<Eigen::Vector3d>& points,
                                         std::vector<Eigen::Vector3d>* u, int threads = 0);

}  // namespace fvm::stage
