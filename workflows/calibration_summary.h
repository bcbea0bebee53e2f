#pragma once
// What `fvm calibrate` tells its user, built from the run (calibrate_job.h) for every front end alike: the JSON
// document (`--json`, the file `-o` and Python's Calibration.save() write, Calibration.summary), the printed table
// and the report's data (`--report DIR`, fvm.write_report). The batch route here, the scan route in
// scan_calibration_summary.cc; the pieces both share (the validation block and its rows, the parameter table, the
// report) are declared here too.

#include <nlohmann/json.hpp>
#include <string>

#include "report/stage_report.h"
#include "stage/identification.h"
#include "stage/stitched_frame.h"
#include "workflows/calibrate.h"
#include "workflows/calibrate_job.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// The batch route: the calibration file (stage::CalibrationToJson) with "batch", "anchor", "stitched_frame",
// "raw_exports" (a batch of surfaces: {"centres_dir", "exports": [{"file", "calottes", "rejected"}]}),
// "identification" {"placements", "before_mean_um", ...} and "validation" (validation placements only); the report
// whenever the run judged a set (its validation placements, or its identification ones when asked).
Summary Summarize(const BatchCalibrationRun& run);
// The scan route: the calibration file with "stitched_frame", "pixel_mm", "pixel_u_mm", "distortion", "scans",
// "cannot_tell", "predicted_xy_u_um" and "validation" (with --validate); the report only with --validate.
Summary Summarize(const ScanCalibrationRun& run);

// What a batch of raw exports gave, as the command prints it while it goes on: a line per surface, and where the
// centre exports went (`centres_dir` empty: not written).
std::string RawExportsText(const artefacts::RawExportBatch& raw, const std::string& artefact, const std::string& centres_dir);

// The "validation" block: held-out placements before and after, in the given frame.
nlohmann::json ValidationJson(const BeforeAfter& judged, stage::StitchedFrame frame);
// Its rows of the printed table.
std::string ValidationText(const BeforeAfter& judged, stage::StitchedFrame frame);
// The table of free coefficients with their standard uncertainties, and those fixed at 0 with why.
std::string ParameterTable(const stage::IdentificationResult& result);
// The report of a calibration judged on `shown` (the set `judged` is of), `shown_what` saying which set it is.
report::ReportData CalibrationReport(const std::string& source, const stage::IdentificationResult& result,
                                     const stage::MeasurementSet& shown, const std::string& shown_what,
                                     const BeforeAfter& judged, stage::StitchedFrame frame);

}  // namespace fvm::workflows
