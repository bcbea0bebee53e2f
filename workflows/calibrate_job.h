#pragma once
// `fvm calibrate` as one job, for the command line and the Python module alike: its options (one struct, as the
// command spells them), the batch route (centre exports, or raw surface exports searched for the artefact's
// calottes) and the scan route (stitched calibration scans, optionally with the objective's field distortion),
// each returning a run that owns what it read and found; calibration_summary.h turns a run into its summary.

#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "artefacts/io/raw_export_batch.h"
#include "workflows/calibrate.h"
#include "workflows/distortion_options.h"
#include "workflows/model_choice.h"
#include "workflows/scan_distortion.h"

namespace fvm::workflows {

struct CalibrateJobOptions {
  ModelChoice model;          // --model, --terms
  IdentifySettings settings;  // --anchor, --stitched-frame, --loss, --loss-scale-um; threads
  // A batch of raw surface exports: the artefact whose calottes are searched (--artefact), and where the centre
  // exports found go as a CSV batch (--centres-dir; empty: not written).
  std::string artefact = "bar17";
  std::string centres_dir;
  // Stitched calibration scans: the pixel size on the part and its standard uncertainty (--pixel-mm,
  // --pixel-u-mm, mm), an artefact batch whose validation placements judge the result (--validate), the field
  // distortion (--distortion, --distortion-file, --save-distortion), a progress line per scan on stderr.
  double pixel_mm = 0.0, pixel_u_mm = 0.0;
  std::string validate;
  DistortionOptions distortion;
  bool progress = false;
  // A batch without validation placements: judge the identification ones anyway (what a report shows).
  bool judge_identification = false;

  // The scan route's options: throws InputError naming --pixel-mm, --pixel-u-mm or the distortion options.
  void CheckScans() const;
};

// What a batch was read from and what it holds.
struct CalibrationBatchInput {
  std::string source;  // the batch directory as given ("arrays" for one given as arrays)
  artefacts::Batch batch;
  std::optional<artefacts::RawExportBatch> raw;  // the surfaces' fits, for a batch of raw exports
};

// Reads the batch directory: centre exports, or raw exports whose centres found are written into
// options.centres_dir when it is given. Throws InputError naming the file.
CalibrationBatchInput ReadCalibrationBatch(const std::string& dir, const CalibrateJobOptions& options);

// A batch calibrated, with what it was read from.
struct BatchCalibrationRun {
  CalibrateJobOptions options;
  CalibrationBatchInput input;
  BatchCalibration calibration;
};

// Throws InputError naming the model when the batch cannot carry it.
BatchCalibrationRun CalibrateBatchInput(CalibrationBatchInput input, const CalibrateJobOptions& options);
// ReadCalibrationBatch, then CalibrateBatchInput.
BatchCalibrationRun CalibrateBatchDirectory(const std::string& dir, const CalibrateJobOptions& options);

// Stitched scans calibrated, with their registrations.
struct ScanCalibrationRun {
  CalibrateJobOptions options;
  std::vector<std::string> layouts;
  std::vector<artefacts::RegisteredScan> scans;
  std::optional<ScanDistortion> field;  // with --distortion / --distortion-file
  ScanCalibrationResult calibration;
};

// Checks the options (CheckScans), reads and registers the scans (without the field when asked, which is then
// saved to options.distortion.save when given), reads the validation batch and calibrates. Throws InputError
// naming the layout, file or option.
ScanCalibrationRun CalibrateScanLayouts(const std::vector<std::string>& layouts, const CalibrateJobOptions& options);

}  // namespace fvm::workflows
