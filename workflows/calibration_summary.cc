#include "workflows/calibration_summary.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "stage/calibration.h"
#include "stage/io/calibration_file.h"
#include "stage/parameter_layout.h"
#include "stage/validation.h"

namespace fvm::workflows {
namespace {

nlohmann::json CalibrationStatsJson(const stage::ValidationStats& s) {
  return {{"centres", s.count}, {"mean_um", s.mean_mm * 1e3}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
          {"predicted_rms_um", s.predicted_rms_mm * 1e3}, {"predicted_undetermined_rms_um", s.undetermined_rms_mm * 1e3}};
}

nlohmann::json CalibrationFrameFreeJson(const stage::FrameFreeStats& s) {
  return {{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3}, {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
}

double LargestAbs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// What the first-tile figure did with each measurement's turn, for people.
std::string TurnText(const stage::ValidationStats& s, stage::StitchedFrame frame) {
  if (s.turn == "model") return "each placement turned by the model's " + JoinNames(s.turn_coefficients);
  if (s.turn == "uncertainty") {
    return fmt::format("the model cannot tell the turn, so the prediction carries its spread over the placements "
                       "({:.1f} urad about z)", s.turn_u_rad.z() * 1e6);
  }
  return frame == stage::StitchedFrame::kTranslated ? "no turn" : "no model, no turn";
}

// One row of the validation table: what, the mean (text, empty for frame-free figures), rms and max, and the
// predicted rms when asked.
template <typename Stats>
std::string ValidationRow(const std::string& what, const Stats& s, const std::string& mean, bool predicted) {
  return fmt::format("  {:<34} {:>8} {:>8.2f} {:>8.2f}", what, mean, s.rms_mm * 1e3, s.max_mm * 1e3) +
         fmt::format("{}\n", predicted ? fmt::format("   (predicted rms {:.2f})", s.predicted_rms_mm * 1e3) : "");
}

std::string BatchHeaderText(const BatchCalibrationRun& run) {
  const stage::IdentificationResult& result = run.calibration.result;
  const stage::Calibration& cal = result.calibration;
  std::string text = fmt::format("fvm calibrate: model {} ({} chain, eq. 1) on {}\n", cal.model, cal.layout.chain().code,
                                 run.input.source);
  text += fmt::format("  identification: {} ({} centres), anchor {}\n", JoinNames(run.input.batch.identify),
                      result.residuals.size(), run.options.settings.anchor);
  text += fmt::format("  solver: {} in {} iterations; condition number {:.3g}\n",
                      result.converged ? "converged" : "NOT converged", result.iterations, result.condition_number);
  return text;
}

std::string BatchText(const BatchCalibrationRun& run) {
  const stage::IdentificationResult& result = run.calibration.result;
  const stage::ValidationStats& before = run.calibration.identification_before;
  std::string text = BatchHeaderText(run) + ParameterTable(result);
  text += fmt::format("\n  {:<34} {:>8} {:>8} {:>8}\n", "3D centre error (um)", "mean", "rms", "max");
  text += fmt::format("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", "identification, before", before.mean_mm * 1e3,
                      before.rms_mm * 1e3, before.max_mm * 1e3);
  text += fmt::format("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", "identification, after", result.residual_summary.mean_um(),
                      result.residual_summary.rms_um(), result.residual_summary.max_um());
  if (run.calibration.validation) text += ValidationText(*run.calibration.judged, run.options.settings.Frame());
  return text;
}

nlohmann::json RawExportsJson(const artefacts::RawExportBatch& raw, const std::string& centres_dir) {
  nlohmann::json j;
  j["centres_dir"] = centres_dir.empty() ? nlohmann::json(nullptr) : nlohmann::json(centres_dir);
  for (const artefacts::RawExportFit& fit : raw.fits) {
    j["exports"].push_back({{"file", fit.file.string()}, {"calottes", fit.centres.centres.size()}, {"rejected", fit.rejected}});
  }
  return j;
}

nlohmann::json BatchJson(const BatchCalibrationRun& run) {
  const BatchCalibration& c = run.calibration;
  nlohmann::json doc = stage::CalibrationToJson(c.result);
  if (run.input.raw) doc["raw_exports"] = RawExportsJson(*run.input.raw, run.options.centres_dir);
  doc["batch"] = run.input.source;
  doc["anchor"] = run.options.settings.anchor;
  doc["stitched_frame"] = run.options.settings.stitched_frame;
  doc["identification"]["placements"] = run.input.batch.identify;
  doc["identification"]["before_mean_um"] = c.identification_before.mean_mm * 1e3;
  if (c.validation) {
    doc["validation"] = ValidationJson(*c.judged, run.options.settings.Frame());
    doc["validation"]["placements"] = run.input.batch.validate;
  }
  return doc;
}

}  // namespace

std::string RawExportsText(const artefacts::RawExportBatch& raw, const std::string& artefact, const std::string& centres_dir) {
  std::string text;
  for (const artefacts::RawExportFit& fit : raw.fits) {
    text += fmt::format("{}: {} calottes of {} found\n", fit.file.string(), fit.centres.centres.size(), artefact);
  }
  text += fmt::format("{}\n\n", centres_dir.empty() ? "centre exports not written (give --centres-dir DIR to keep them)"
                                                     : "centre exports written to " + centres_dir);
  return text;
}

nlohmann::json ValidationJson(const BeforeAfter& judged, stage::StitchedFrame frame) {
  const Judgement& before = judged.before;
  const Judgement& after = judged.after;
  nlohmann::json v = CalibrationStatsJson(after.first_tile);
  v["rigid"] = CalibrationFrameFreeJson(after.rigid);
  v["distances"] = CalibrationFrameFreeJson(after.distances);
  v["stitched_frame"] = stage::StitchedFrameName(frame);
  v["turn"] = after.first_tile.turn;
  v["turn_note"] = TurnText(after.first_tile, frame);
  v["turn_coefficients"] = after.first_tile.turn_coefficients;
  const Eigen::Vector3d& u = after.first_tile.turn_u_rad;
  v["turn_u_urad"] = {u.x() * 1e6, u.y() * 1e6, u.z() * 1e6};
  v["before"] = CalibrationStatsJson(before.first_tile);
  v["before"]["rigid"] = CalibrationFrameFreeJson(before.rigid);
  v["before"]["distances"] = CalibrationFrameFreeJson(before.distances);
  v["distance_error_max_um"] = {{"before", LargestAbs(judged.distance_errors_before_mm) * 1e3},
                                {"after", LargestAbs(judged.distance_errors_after_mm) * 1e3}};
  return v;
}

std::string ValidationText(const BeforeAfter& judged, stage::StitchedFrame frame) {
  const Judgement& before = judged.before;
  const Judgement& after = judged.after;
  std::string text = fmt::format("  validation, {} centres; first what no choice of frame changes:\n", after.first_tile.count);
  text += ValidationRow("rigid fit per placement, before", before.rigid, "", false);
  text += ValidationRow("rigid fit per placement, after", after.rigid, "", true);
  text += ValidationRow(fmt::format("distances ({} pairs), before", after.distances.count), before.distances, "", false);
  text += ValidationRow("distances, after", after.distances, "", true);
  text += fmt::format("  then each placement in its first tile's frame ({}: {}):\n", stage::StitchedFrameName(frame),
                      TurnText(after.first_tile, frame));
  text += ValidationRow("first tile, before", before.first_tile, fmt::format("{:.2f}", before.first_tile.mean_mm * 1e3), false);
  text += ValidationRow("first tile, after", after.first_tile, fmt::format("{:.2f}", after.first_tile.mean_mm * 1e3), true);
  text += fmt::format("  largest distance error on validation: {:.1f} um before, {:.2f} um after\n",
                      LargestAbs(judged.distance_errors_before_mm) * 1e3, LargestAbs(judged.distance_errors_after_mm) * 1e3);
  return text;
}

std::string ParameterTable(const stage::IdentificationResult& r) {
  const stage::Calibration& cal = r.calibration;
  const Eigen::VectorXd u = cal.StandardUncertainty();
  std::string text = fmt::format("\n  {:<8} {:>12} {:>10}   {}\n", "param", "value", "u (k=1)", "unit");
  for (const std::string& name : cal.layout.FreeNames()) {
    const int slot = cal.layout.FreeIndexOf(name);
    const auto& c = cal.layout.coefficients()[static_cast<size_t>(cal.layout.FindCoefficient(name))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    text += fmt::format("  {:<8} {:>12.3f} {:>10.3f}   {}\n", name, cal.values[static_cast<size_t>(slot)] * unit.per_si,
                        u[slot] * unit.per_si, unit.name);
  }
  if (!r.fixed.empty()) {
    text += "\n  fixed at 0 (the data cannot determine them):\n";
    for (const stage::FixedCoefficient& f : r.fixed) text += fmt::format("  {:<8} {}\n", f.name, f.reason);
  }
  return text;
}

report::ReportData CalibrationReport(const std::string& source, const stage::IdentificationResult& r,
                                     const stage::MeasurementSet& shown, const std::string& shown_what,
                                     const BeforeAfter& judged, stage::StitchedFrame frame) {
  report::ReportData data;
  data.title = fmt::format("fvm calibrate: model {} on {}", r.calibration.model, source);
  const Judgement& judged_after = judged.after;
  const stage::ValidationStats& before = judged.before.first_tile;
  const stage::ValidationStats& after = judged_after.first_tile;
  const auto frame_free = [](const stage::FrameFreeStats& s) {
    return fmt::format("{:.2f} rms / {:.2f} max um (predicted rms {:.2f})", s.rms_mm * 1e3, s.max_mm * 1e3, s.predicted_rms_mm * 1e3);
  };
  data.summary = {{"model", r.calibration.model},
                  {"free parameters", std::to_string(r.calibration.layout.NumFree())},
                  {"fixed (not identifiable)", std::to_string(r.fixed.size())},
                  {"identification rms", fmt::format("{:.2f} um", r.residual_summary.rms_um())},
                  {"shown data", shown_what},
                  {"rigid fit per placement, after", frame_free(judged_after.rigid)},
                  {"distances, all pairs, after", frame_free(judged_after.distances)},
                  {"first tile, before (mean / max)", fmt::format("{:.1f} / {:.1f} um", before.mean_mm * 1e3, before.max_mm * 1e3)},
                  {"first tile, after (mean / max)", fmt::format("{:.2f} / {:.2f} um (predicted rms {:.2f})", after.mean_mm * 1e3,
                                                                 after.max_mm * 1e3, after.predicted_rms_mm * 1e3)},
                  {"first-tile frame", fmt::format("{}: {}", stage::StitchedFrameName(frame), TurnText(after, frame))},
                  {"condition number", fmt::format("{:.3g}", r.condition_number)}};
  for (double e : judged.distance_errors_before_mm) data.distance_errors_before_um.push_back(e * 1e3);
  for (double e : judged.distance_errors_after_mm) data.distance_errors_after_um.push_back(e * 1e3);
  for (size_t i = 0; i < shown.observations.size(); ++i) {
    const Eigen::Vector3d& q = shown.observations[i].command;
    data.errors_before.push_back({q.x(), q.y(), -before.residuals[i].x() * 1e3, -before.residuals[i].y() * 1e3});
    data.errors_after.push_back({q.x(), q.y(), -after.residuals[i].x() * 1e3, -after.residuals[i].y() * 1e3});
  }
  const Eigen::VectorXd u = r.calibration.StandardUncertainty();
  for (const std::string& name : r.calibration.layout.FreeNames()) {
    const int slot = r.calibration.layout.FreeIndexOf(name);
    const auto& c = r.calibration.layout.coefficients()[static_cast<size_t>(r.calibration.layout.FindCoefficient(name))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    data.parameters.push_back({name, r.calibration.values[static_cast<size_t>(slot)] * unit.per_si, u[slot] * unit.per_si, unit.name});
  }
  return data;
}

Summary Summarize(const BatchCalibrationRun& run) {
  Summary summary{BatchJson(run), BatchText(run), std::nullopt};
  const BatchCalibration& c = run.calibration;
  if (c.judged) {
    summary.report = CalibrationReport(run.input.source, c.result, c.Shown(),
                                       c.validation ? "validation placements" : "identification placements", *c.judged,
                                       run.options.settings.Frame());
  }
  return summary;
}

}  // namespace fvm::workflows
