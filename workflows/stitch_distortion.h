#pragma once
// `fvm stitch --distortion [ORDER]` / `--distortion-file F`: the tiles placed without the objective's field
// distortion. From the rigid registration (workflows/stitch.h), dense correspondences in every accepted overlap
// (imaging/overlap_correspondences.h) and one joint solve of the positions and the field
// (imaging/field_distortion_fit.h), twice: the second time the correspondences start where the first field puts
// them. With a known field only the positions are solved. Then the tiles are resampled without the field and
// judged by their overlap correlation at the new positions, beside the raw tiles' at the rigid ones.

#include <optional>
#include <vector>

#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"
#include "imaging/overlap_correlation.h"
#include "imaging/overlap_correspondences.h"
#include "workflows/stitch.h"

namespace fvm::workflows {

struct StitchDistortionOptions {
  int order = 3;                                // the field to identify (FieldDistortionTermNames)
  std::optional<imaging::FieldDistortion> known;  // a saved field of the same objective: not identified again
  imaging::CorrespondenceOptions matching;
  imaging::FieldDistortionFitOptions fit;         // its order and hold_stretch_terms are set from the two above
  // A grid is placed by its overlaps alone: the terms that act on them as a stretch or shear of the mosaic are held
  // at 0 (imaging::kHeldStretchTerms), as the published method holds them.
  bool hold_stretch_terms = true;
  // The rigid registration's options (StitchOptions::registration), for the grid registered again on the tiles
  // resampled without the field when the raw tiles left pairs unregistered.
  imaging::RegistrationOptions registration;
  void Check() const;  // throws std::invalid_argument
};

struct StitchDistortionResult {
  imaging::FieldDistortionFit fit;  // the field, the positions of the undistorted tiles and their covariance
  bool identified = false;          // false: the known field, positions only
  std::vector<imaging::TileImage> undistorted;  // NaN where the raw tile does not reach
  std::vector<imaging::PairOverlapCorrelation> overlap_ncc;  // undistorted tiles at the new positions
  double mean_overlap_ncc_before = NAN, mean_overlap_ncc_after = NAN;
  // Each position's standard uncertainty per axis (px), against the first tile: what TilePositions::sigma_px says
  // for the rigid solve, the field's uncertainty included.
  std::vector<Eigen::Vector2d> sigma_px;
  // Pairs the rigid registration rejected on the raw tiles that registered on the tiles resampled without the
  // field (the field sheared their overlaps): the field and the positions were identified again with them.
  int pairs_registered_undistorted = 0;
  // The registration whose accepted pairs the field and the positions were identified from, and whose tiles it
  // places on both axes (positions.registered) the positions rest on: the rigid one on the raw tiles, or the grid
  // registered again on the undistorted tiles when that registered more pairs (pairs_registered_undistorted > 0).
  imaging::RegistrationResult registration;
};

// `rigid`: StitchTiles on the same `images`. Throws imaging::FieldDistortionUndeterminable (a strip in one
// direction, texture-free overlaps, too high an order), naming what the overlaps cannot tell.
StitchDistortionResult StitchWithoutDistortion(const StitchResult& rigid, const std::vector<imaging::TileImage>& images,
                                               const StitchDistortionOptions& options);

}  // namespace fvm::workflows
