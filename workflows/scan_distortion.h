#pragma once
// `fvm calibrate --scan ... --distortion [ORDER]` / `--distortion-file F`: the calibration scans registered without
// the objective's field distortion. Registered as chains (calibration_scans.h); while each scan's tiles are in
// memory, dense correspondences in every accepted overlap (imaging/overlap_correspondences.h); then one joint solve
// of all scans' tile positions (each scan's first tile holds) and the one field they share
// (imaging/field_distortion_fit.h). A row sees how the field changes along x, a column along y: together they
// determine it, one direction alone does not (refused by name). Each pair's offset and the chained positions are
// then those of the undistorted tiles, and the stage calibration reads them as it reads rigid ones: a pair whose
// overlap gave the fit too few correspondences (a diagonal's corner, a thin band of small tiles) is registered
// again on its tiles resampled without the field.

#include <optional>
#include <string>
#include <vector>

#include "artefacts/scan_observations.h"
#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"
#include "imaging/overlap_correspondences.h"

namespace fvm::workflows {

struct ScanDistortionOptions {
  int order = 3;
  std::optional<imaging::FieldDistortion> known;  // a saved field: positions only
  imaging::CorrespondenceOptions matching;
  imaging::FieldDistortionFitOptions fit;
  // Identified: match every overlap again from the field found, b's windows warped to a's view (a second read of
  // the tiles), and fit again. Off: the first round's field (own-axis cubic biased by the views' stretch).
  bool rematch = true;
};

struct ScanDistortion {
  imaging::FieldDistortionFit fit;  // positions_px: every scan's tiles in turn, each scan from its first tile
  bool identified = false;
};

// ReadAndRegisterScans, the field identified (or taken) and taken out of every pair's offset and every chained
// position. Each pair keeps the information of its registration: the field's own uncertainty, shared by every
// pair, is in `field->fit`, not in the pairs' weights. Throws InputError for what the overlaps cannot determine.
std::vector<artefacts::RegisteredScan> ReadAndRegisterUndistortedScans(const std::vector<std::string>& layouts,
                                                                       double pixel_mm, int threads, bool progress,
                                                                       const ScanDistortionOptions& options,
                                                                       ScanDistortion* field);

}  // namespace fvm::workflows
