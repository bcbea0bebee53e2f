#pragma once
// The scan half of `fvm correct` (workflows/correct_files.h): a point cloud (XYZ, PLY, PCD) or a height map (X3P,
// AL3D, TIFF) corrected point by point with a stage model (stage/scan_correction.h), or, with a tile layout, tile by
// tile (one rigid shift per tile at its stage position). Reads, corrects, writes.

#include "stage/calibration.h"
#include "workflows/correct_files.h"

namespace fvm::workflows {

// options.input to options.output (a file in the scan's family), its uncertainties beside a height map. Throws
// InputError for bad input or an output format the input cannot become, naming what to give instead.
CorrectedFiles CorrectScanFile(const CorrectOptions& options, const stage::Calibration& calibration);

// The tiles of options.layout into the directory options.output, with shifts.csv.
CorrectedFiles CorrectTileFiles(const CorrectOptions& options, const stage::Calibration& calibration);

}  // namespace fvm::workflows
