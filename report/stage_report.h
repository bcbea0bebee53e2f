#pragma once
// The human-facing report of `fvm calibrate --report DIR` (and later `compare`, `diagnose`): an HTML page with a
// summary table and three SVG plots a metrologist reads to judge a calibration. Units here are the report's:
// micrometres and microradians for errors and parameters, millimetres for stage positions.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fvm::report {

struct ReportData {
  std::string title;                                         // e.g. "fvm calibrate: model 27 on samples/bar17"
  std::vector<std::pair<std::string, std::string>> summary;  // key/value rows for a table at the top
  std::vector<double> distance_errors_before_um;             // histogram: before compensation
  std::vector<double> distance_errors_after_um;              // histogram: after compensation (same axes)
  struct ErrorVector {
    double x_mm, y_mm, dx_um, dy_um;
  };
  std::vector<ErrorVector> errors_before, errors_after;  // lateral error vectors at stage positions
  struct Parameter {
    std::string name;
    double value, uncertainty;  // uncertainty is the standard uncertainty u; the plot shows +-2u
    std::string unit;           // "um" or "urad" (other units get their own panel too)
  };
  std::vector<Parameter> parameters;  // with error bars (+-2 u), grouped by unit
  // The stage travel drawn to scale under the error vectors; the default is the Alicona G5's 200 x 200 mm in the
  // coordinates of its exports (stage::FvmStageTravel()). The plot widens to show positions outside it.
  struct StageArea {
    double x_min_mm = -200.0, x_max_mm = 0.0, y_min_mm = -200.0, y_max_mm = 0.0;
  };
  StageArea stage_area;
  // What separates "before" from "after" in titles, legends and captions: the compensation for `fvm calibrate`,
  // the added effect for `fvm diagnose`.
  std::string change = "compensation";
  // `fvm diagnose`: the model after each step of the forward selection, the base model first. When given, the
  // report gains steps.svg: both mean residuals, step by step.
  struct Step {
    std::string label;                       // "base model", "+ thermal_drift x", ...
    double identification_um, held_out_um;   // mean 3-D residuals; held_out_um NaN when there are none
  };
  std::vector<Step> steps;
};

// Writes DIR/index.html and the SVG plots it shows (distance_errors.svg, error_vectors.svg, parameters.svg, and
// steps.svg when there are steps).
// Creates DIR if needed; each file is written atomically, the page last, so it never shows a missing plot.
// Throws fvm::InputError naming DIR when it cannot be written, and then leaves no file it created behind.
// Not thread-safe: PLplot keeps its streams in process-wide state. The caller's current PLplot stream is kept.
void WriteReport(const std::filesystem::path& dir, const ReportData& data);

}  // namespace fvm::report
