// What `fvm diagnose` prints, its --json document and its report's data, from the diagnosis itself.

#include <fmt/core.h>
#include <fmt/format.h>

#include <cmath>

#include "workflows/diagnose.h"

namespace fvm::workflows {
namespace {

nlohmann::json ResidualJson(const stage::ResidualSummary& s) {
  return {{"centres", s.count}, {"mean_um", s.mean_mm * 1e3}, {"rms_um", s.rms_mm * 1e3}};
}

// A step's alternatives, for the text and the report alike.
std::string AlternativesSentence(const stage::DiagnosisStep& s) {
  return fmt::format("These data fit {} exactly as well: one cannot be told from the other here.", fmt::join(s.alternatives, ", "));
}

nlohmann::json StepJson(const stage::DiagnosisStep& s) {
  return {{"effect", s.effect},
          {"component", s.component},
          {"explanation", s.explanation},
          {"size", {{"value", s.size}, {"u", s.size_u}, {"unit", s.size_unit}}},
          {"alternatives", s.alternatives},
          {"before", ResidualJson(s.before)},
          {"after", ResidualJson(s.after)},
          {"validation", {{"before", ResidualJson(s.validation_before)}, {"after", ResidualJson(s.validation_after)}}}};
}

nlohmann::json DiagnosisJson(const stage::Diagnosis& d, const DiagnoseOptions& options) {
  nlohmann::json doc;
  doc["model"] = options.model.Name();
  doc["effect"] = d.effect ? nlohmann::json(*d.effect) : nlohmann::json(nullptr);
  doc["component"] = d.component;
  doc["explanation"] = d.explanation;
  doc["before"] = ResidualJson(d.before);
  doc["after"] = ResidualJson(d.after);
  doc["validation"] = {{"before", ResidualJson(d.validation_before)}, {"after", ResidualJson(d.validation_after)}};
  doc["size"] = {{"value", d.size}, {"u", d.size_u}, {"unit", d.size_unit}};
  doc["findings"] = d.findings;
  doc["effects"] = nlohmann::json::array();
  for (const stage::DiagnosisStep& s : d.steps) doc["effects"].push_back(StepJson(s));
  doc["notes"] = d.notes;
  doc["unexplained"] = d.unexplained.empty() ? nlohmann::json(nullptr) : nlohmann::json(d.unexplained);
  doc["stitched_frame"] = options.settings.stitched_frame;
  for (const stage::PlacementTurnFinding& t : d.turns) {
    doc["turns"].push_back({{"placement", t.placement},
                            {"rotation_urad", {t.rotation_rad.x() * 1e6, t.rotation_rad.y() * 1e6, t.rotation_rad.z() * 1e6}},
                            {"u_urad", {t.u_rad.x() * 1e6, t.u_rad.y() * 1e6, t.u_rad.z() * 1e6}}});
  }
  for (const stage::EffectScore& c : d.candidates) {
    doc["candidates"].push_back({{"effect", c.effect}, {"component", c.component}, {"extra_parameters", c.extra_parameters},
                                 {"f", c.f_statistic}, {"p_value", c.p_value}, {"delta_bic", c.delta_bic},
                                 {"significant", c.significant}});
  }
  return doc;
}

// The findings, the best candidates and the steps accepted, each with what it explains.
std::string StepsText(const stage::Diagnosis& d) {
  std::string text = "  residual analysis:\n";
  for (const std::string& f : d.findings) text += fmt::format("    - {}\n", f);
  text += fmt::format("\n  {:<22} {:>6} {:>10} {:>10} {:>9}\n", "candidate", "extra", "F", "p", "dBIC");
  for (size_t i = 0; i < d.candidates.size() && i < 6; ++i) {
    const stage::EffectScore& c = d.candidates[i];
    text += fmt::format("  {:<22} {:>6} {:>10.3g} {:>10.2g} {:>9.1f}{}\n", c.effect + (c.component.empty() ? "" : " " + c.component),
                        c.extra_parameters, c.f_statistic, c.p_value, c.delta_bic, c.significant ? "  significant" : "");
  }
  if (d.steps.empty()) text += fmt::format("\n  effect: none\n  {}\n\n", d.explanation);
  for (size_t k = 0; k < d.steps.size(); ++k) {
    const stage::DiagnosisStep& s = d.steps[k];
    text += fmt::format("\n  step {}: {}{}, {:.3g} +- {:.2g} {}; held-out mean {:.2f} -> {:.2f} um\n", k + 1, s.effect,
                        s.component.empty() ? "" : " (" + s.component + ")", s.size, s.size_u, s.size_unit,
                        s.validation_before.mean_mm * 1e3, s.validation_after.mean_mm * 1e3);
    text += fmt::format("  {}\n", s.explanation);
    if (!s.alternatives.empty()) text += fmt::format("  {}\n", AlternativesSentence(s));
  }
  for (const std::string& note : d.notes) text += fmt::format("  note: {}\n", note);
  if (!d.unexplained.empty()) text += fmt::format("\n  {}\n", d.unexplained);
  return text + "\n";
}

// The turns found and the mean residuals before and after.
std::string FiguresText(const stage::Diagnosis& d) {
  std::string text;
  if (!d.turns.empty()) {
    text += fmt::format("  {:<16} {:>22}\n", "placement", "yaw about first tile");
    for (const stage::PlacementTurnFinding& t : d.turns) {
      text += fmt::format("  {:<16} {:>12.1f} +- {:.1f} urad\n", t.placement, t.rotation_rad.z() * 1e6, t.u_rad.z() * 1e6);
    }
    text += "\n";
  }
  text += fmt::format("  {:<28} {:>9} {:>9}\n", "mean 3D residual (um)", "before", "after");
  text += fmt::format("  {:<28} {:>9.2f} {:>9.2f}\n", "identification", d.before.mean_mm * 1e3, d.after.mean_mm * 1e3);
  if (d.validation_before.count > 0) {
    text += fmt::format("  {:<28} {:>9.2f} {:>9.2f}\n", "held-out placements", d.validation_before.mean_mm * 1e3,
                        d.validation_after.mean_mm * 1e3);
  }
  return text;
}

// The summary table's rows: the effect, the residuals, each step with its held-out figures, the notes.
void ReportRows(const stage::Diagnosis& d, report::ReportData& data) {
  data.summary = {{"effect", d.effect.value_or("none")},
                  {"component", d.component.empty() ? "-" : d.component},
                  {"explanation", d.explanation},
                  {"residual before (mean / rms)", fmt::format("{:.2f} / {:.2f} um", d.before.mean_mm * 1e3, d.before.rms_mm * 1e3)},
                  {"residual after (mean / rms)", fmt::format("{:.2f} / {:.2f} um", d.after.mean_mm * 1e3, d.after.rms_mm * 1e3)}};
  if (d.validation_before.count > 0) {
    data.summary.emplace_back("held-out placements (mean before / after)",
                              fmt::format("{:.2f} / {:.2f} um", d.validation_before.mean_mm * 1e3, d.validation_after.mean_mm * 1e3));
  }
  for (const std::string& f : d.findings) data.summary.emplace_back("residual analysis", f);
}

report::ReportData DiagnosisReport(const BatchDiagnosis& diagnosis, const DiagnoseOptions& options, const std::string& batch_name) {
  const stage::Diagnosis& d = diagnosis.diagnosis;
  const stage::MeasurementSet& identify = diagnosis.identification;
  report::ReportData data;
  data.title = fmt::format("fvm diagnose: model {} on {}", options.model.Name(), batch_name);
  std::string added;
  for (const stage::DiagnosisStep& s : d.steps) added += (added.empty() ? "adding " : ", then ") + s.effect;
  data.change = d.steps.empty() ? "(no effect accepted)" : added;
  ReportRows(d, data);
  for (double e : diagnosis.distance_errors_before_mm) data.distance_errors_before_um.push_back(e * 1e3);
  for (double e : diagnosis.distance_errors_after_mm) data.distance_errors_after_um.push_back(e * 1e3);
  // Residuals after taking outliers out belong to fewer centres: then the map shows the centres before only.
  const bool after_in_step = d.residuals_after.size() == identify.observations.size();
  for (size_t i = 0; i < identify.observations.size() && i < d.residuals_before.size(); ++i) {
    const Eigen::Vector3d& q = identify.observations[i].command;
    data.errors_before.push_back({q.x(), q.y(), -d.residuals_before[i].x() * 1e3, -d.residuals_before[i].y() * 1e3});
    if (after_in_step) data.errors_after.push_back({q.x(), q.y(), -d.residuals_after[i].x() * 1e3, -d.residuals_after[i].y() * 1e3});
  }
  const auto held_out_um = [](const stage::ResidualSummary& s) { return s.count > 0 ? s.mean_mm * 1e3 : std::nan(""); };
  data.steps.push_back({"base model", d.before.mean_mm * 1e3, held_out_um(d.validation_before)});
  for (const stage::DiagnosisStep& s : d.steps) {
    data.steps.push_back({"+ " + s.effect + (s.component.empty() ? "" : " " + s.component), s.after.mean_mm * 1e3,
                          held_out_um(s.validation_after)});
  }
  for (size_t k = 0; k < d.steps.size(); ++k) {
    const stage::DiagnosisStep& s = d.steps[k];
    data.summary.emplace_back(fmt::format("step {}: {}", k + 1, s.effect),
                              fmt::format("held-out mean {:.2f} -> {:.2f} um; {}{}", s.validation_before.mean_mm * 1e3,
                                          s.validation_after.mean_mm * 1e3, s.explanation,
                                          s.alternatives.empty() ? "" : " " + AlternativesSentence(s)));
    data.parameters.push_back({s.effect + (s.component.empty() ? "" : " " + s.component), s.size, s.size_u, s.size_unit});
  }
  for (const std::string& note : d.notes) data.summary.emplace_back("note", note);
  if (!d.unexplained.empty()) data.summary.emplace_back("unexplained", d.unexplained);
  return data;
}

}  // namespace

Summary Summarize(const BatchDiagnosis& diagnosis, const DiagnoseOptions& options, const std::string& batch_name) {
  const stage::Diagnosis& d = diagnosis.diagnosis;
  Summary summary;
  summary.json = DiagnosisJson(d, options);
  summary.text = fmt::format("fvm diagnose: model {} on {} ({} identification centres, {} held out)\n\n", options.model.Name(),
                             batch_name, diagnosis.identification.observations.size(), diagnosis.validation.observations.size());
  summary.text += StepsText(d) + FiguresText(d);
  summary.report = DiagnosisReport(diagnosis, options, batch_name);
  return summary;
}

}  // namespace fvm::workflows
