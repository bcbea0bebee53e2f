#pragma once
// fvm correct on a scan: a point cloud (XYZ, PLY, PCD) or a height map (X3P, AL3D, TIFF) corrected point by point
// with a stage model (stage/scan_correction.h), or, with a tile layout, tile by tile (one rigid shift per tile at
// its stage position). fvm/correct.cc parses the options; this file reads, corrects and writes.

#include <string>

#include "imaging/io/surface_file.h"
#include "stage/calibration.h"
#include "stage/scan_correction.h"

namespace fvm::cli {

struct ScanCorrectionArgs {
  std::string calibration;  // for messages and the header
  std::string input;        // the scan (ignored with a layout)
  std::string output;       // a file in the scan's family; with a layout, a directory
  std::string layout;       // tile layout file,row,col,x,y: correct each tile by one rigid shift
  double resample_mm = 0.0;  // > 0: a height map on a regular grid of this pixel again
  bool extrapolate = false;
  bool json = false;
  int threads = 0;
  imaging::SurfaceReadOptions read;
  stage::ScanCorrectionOptions options;
};

// Throws InputError (exit 1) for bad input and nothing written; CLI::ValidationError-like usage mistakes (an
// output format the input cannot become) also as InputError, naming what to give instead.
void RunScanCorrection(const ScanCorrectionArgs& args, const stage::Calibration& calibration);

}  // namespace fvm::cli
