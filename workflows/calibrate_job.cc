#include "workflows/calibrate_job.h"

#include <cmath>
#include <utility>

#include "core/input_error.h"
#include "workflows/calibration_scans.h"
#include "workflows/field_distortion_file.h"

namespace fvm::workflows {

void CalibrateJobOptions::CheckScans() const {
  if (!(pixel_mm > 0.0) || !std::isfinite(pixel_mm)) {
    throw InputError("--scan needs --pixel-mm: the size of a camera pixel on the part (mm), e.g. 0.00275 for the 5x "
                     "lens's 2.82 mm field on 1024 px; it sets the scale of every registered offset");
  }
  if (!(pixel_u_mm >= 0.0) || !std::isfinite(pixel_u_mm)) throw InputError("--pixel-u-mm: give a standard uncertainty >= 0 (mm)");
  distortion.Check();
}

CalibrationBatchInput ReadCalibrationBatch(const std::string& dir, const CalibrateJobOptions& options) {
  if (!artefacts::HoldsRawExports(dir)) return {dir, artefacts::ReadBatch(dir), std::nullopt};
  artefacts::RawExportBatch raw = artefacts::ReadRawExportBatch(dir, {options.artefact});
  if (!options.centres_dir.empty()) artefacts::WriteRawExportCentres(options.centres_dir, raw);
  artefacts::Batch batch = raw.batch;
  return {dir, std::move(batch), std::move(raw)};
}

BatchCalibrationRun CalibrateBatchInput(CalibrationBatchInput input, const CalibrateJobOptions& options) {
  BatchCalibration calibration = CalibrateBatch(input.batch, {options.model, options.settings, options.judge_identification});
  return {options, std::move(input), std::move(calibration)};
}

BatchCalibrationRun CalibrateBatchDirectory(const std::string& dir, const CalibrateJobOptions& options) {
  return CalibrateBatchInput(ReadCalibrationBatch(dir, options), options);
}

ScanCalibrationRun CalibrateScanLayouts(const std::vector<std::string>& layouts, const CalibrateJobOptions& options) {
  options.CheckScans();
  const int threads = options.settings.threads;
  std::vector<artefacts::RegisteredScan> scans;
  std::optional<ScanDistortion> field;
  if (options.distortion.Requested()) {
    ScanDistortionOptions distortion_options;
    distortion_options.order = options.distortion.Order();
    distortion_options.known = options.distortion.Known();
    field.emplace();
    scans = ReadAndRegisterUndistortedScans(layouts, options.pixel_mm, threads, options.progress, distortion_options, &*field);
    if (!options.distortion.save.empty()) WriteFieldDistortion(options.distortion.save, field->fit.field, options.pixel_mm);
  } else {
    scans = ReadAndRegisterScans(layouts, options.pixel_mm, threads, options.progress);
  }
  std::optional<artefacts::Batch> validation_batch;
  if (!options.validate.empty()) validation_batch = artefacts::ReadBatch(options.validate);
  ScanCalibrationResult calibration = CalibrateScans(
      scans, {options.model, options.settings, options.pixel_mm, options.pixel_u_mm}, validation_batch ? &*validation_batch : nullptr);
  return {options, layouts, std::move(scans), std::move(field), std::move(calibration)};
}

}  // namespace fvm::workflows
