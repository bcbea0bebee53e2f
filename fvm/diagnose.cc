// fvm diagnose BATCH --model N: the discrepancy workflow (stage/discrepancy.h) from the command line.

#include <fmt/core.h>
#include <fmt/format.h>

#include <cmath>

#include <nlohmann/json.hpp>

#include "artefacts/io/batch.h"
#include "fvm/identify_options.h"
#include "workflows/diagnose.h"
#include "fvm/commands.h"
#include "report/stage_report.h"
#include "stage/discrepancy.h"

namespace fvm::cli {
namespace {

struct DiagnoseArgs {
  std::string batch;
  workflows::ModelChoice model;
  std::string report;
  double alpha = 0.01;
  bool json = false;
  workflows::IdentifySettings settings;
};

nlohmann::json SummaryJson(const stage::ResidualSummary& s) {
  return {{"centres", s.count}, {"mean_um", s.mean_mm * 1e3}, {"rms_um", s.rms_mm * 1e3}};
}

// A step's alternatives, for the text and the report alike.
std::string AlternativesSentence(const stage::DiagnosisStep& s) {
  return fmt::format("These data fit {} exactly as well: one cannot be told from the other here.", fmt::join(s.alternatives, ", "));
}

report::ReportData MakeDiagnosisReport(const DiagnoseArgs& args, const workflows::BatchDiagnosis& diagnosis) {
  const stage::Diagnosis& d = diagnosis.diagnosis;
  const stage::MeasurementSet& identify = diagnosis.identification;
  report::ReportData data;
  data.title = fmt::format("fvm diagnose: model {} on {}", args.model.Name(), args.batch);
  std::string added;
  for (const stage::DiagnosisStep& s : d.steps) added += (added.empty() ? "adding " : ", then ") + s.effect;
  data.change = d.steps.empty() ? "(no effect accepted)" : added;
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

void Run(const DiagnoseArgs& args) {
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  const workflows::BatchDiagnosis diagnosis =
      workflows::DiagnoseBatch(batch, {args.model, Threaded(args.settings), args.alpha});
  const stage::Diagnosis& d = diagnosis.diagnosis;
  if (!args.report.empty()) report::WriteReport(args.report, MakeDiagnosisReport(args, diagnosis));

  nlohmann::json doc;
  doc["batch"] = args.batch;
  doc["model"] = args.model.Name();
  doc["effect"] = d.effect ? nlohmann::json(*d.effect) : nlohmann::json(nullptr);
  doc["component"] = d.component;
  doc["explanation"] = d.explanation;
  doc["before"] = SummaryJson(d.before);
  doc["after"] = SummaryJson(d.after);
  doc["validation"] = {{"before", SummaryJson(d.validation_before)}, {"after", SummaryJson(d.validation_after)}};
  doc["size"] = {{"value", d.size}, {"u", d.size_u}, {"unit", d.size_unit}};
  doc["findings"] = d.findings;
  doc["effects"] = nlohmann::json::array();
  for (const stage::DiagnosisStep& s : d.steps) {
    doc["effects"].push_back({{"effect", s.effect},
                              {"component", s.component},
                              {"explanation", s.explanation},
                              {"size", {{"value", s.size}, {"u", s.size_u}, {"unit", s.size_unit}}},
                              {"alternatives", s.alternatives},
                              {"before", SummaryJson(s.before)},
                              {"after", SummaryJson(s.after)},
                              {"validation", {{"before", SummaryJson(s.validation_before)}, {"after", SummaryJson(s.validation_after)}}}});
  }
  doc["notes"] = d.notes;
  doc["unexplained"] = d.unexplained.empty() ? nlohmann::json(nullptr) : nlohmann::json(d.unexplained);
  doc["stitched_frame"] = args.settings.stitched_frame;
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
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("fvm diagnose: model {} on {} ({} identification centres, {} held out)\n\n", args.model.Name(), args.batch,
             diagnosis.identification.observations.size(), diagnosis.validation.observations.size());
  fmt::print("  residual analysis:\n");
  for (const std::string& f : d.findings) fmt::print("    - {}\n", f);
  fmt::print("\n  {:<22} {:>6} {:>10} {:>10} {:>9}\n", "candidate", "extra", "F", "p", "dBIC");
  for (size_t i = 0; i < d.candidates.size() && i < 6; ++i) {
    const stage::EffectScore& c = d.candidates[i];
    fmt::print("  {:<22} {:>6} {:>10.3g} {:>10.2g} {:>9.1f}{}\n", c.effect + (c.component.empty() ? "" : " " + c.component),
               c.extra_parameters, c.f_statistic, c.p_value, c.delta_bic, c.significant ? "  significant" : "");
  }
  if (d.steps.empty()) fmt::print("\n  effect: none\n  {}\n\n", d.explanation);
  for (size_t k = 0; k < d.steps.size(); ++k) {
    const stage::DiagnosisStep& s = d.steps[k];
    fmt::print("\n  step {}: {}{}, {:.3g} +- {:.2g} {}; held-out mean {:.2f} -> {:.2f} um\n", k + 1, s.effect,
               s.component.empty() ? "" : " (" + s.component + ")", s.size, s.size_u, s.size_unit,
               s.validation_before.mean_mm * 1e3, s.validation_after.mean_mm * 1e3);
    fmt::print("  {}\n", s.explanation);
    if (!s.alternatives.empty()) fmt::print("  {}\n", AlternativesSentence(s));
  }
  for (const std::string& note : d.notes) fmt::print("  note: {}\n", note);
  if (!d.unexplained.empty()) fmt::print("\n  {}\n", d.unexplained);
  fmt::print("\n");
  if (!d.turns.empty()) {
    fmt::print("  {:<16} {:>22}\n", "placement", "yaw about first tile");
    for (const stage::PlacementTurnFinding& t : d.turns) {
      fmt::print("  {:<16} {:>12.1f} +- {:.1f} urad\n", t.placement, t.rotation_rad.z() * 1e6, t.u_rad.z() * 1e6);
    }
    fmt::print("\n");
  }
  fmt::print("  {:<28} {:>9} {:>9}\n", "mean 3D residual (um)", "before", "after");
  fmt::print("  {:<28} {:>9.2f} {:>9.2f}\n", "identification", d.before.mean_mm * 1e3, d.after.mean_mm * 1e3);
  if (d.validation_before.count > 0) {
    fmt::print("  {:<28} {:>9.2f} {:>9.2f}\n", "held-out placements", d.validation_before.mean_mm * 1e3,
               d.validation_after.mean_mm * 1e3);
  }
  if (!args.report.empty()) fmt::print("\nreport written to {}/index.html\n", args.report);
}

}  // namespace

void RegisterDiagnose(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArgs>();
  CLI::App* sub = app.add_subcommand(
      "diagnose", "find where model and measurements disagree, name the missing effect, add it, show the gap shrink");
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help'); held-out placements confirm")
      ->required();
  sub->add_option("--model", args->model.model, "base model: 9, 15, 27 or 42")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", args->model.terms, "a base model of one's own instead: TERM[:BASIS][:ORDER],... as 'fvm calibrate --terms'");
  sub->add_option("--alpha", args->alpha, "family-wise false-alarm probability of the selection")
      ->check(Within(1e-6, 0.5))
      ->capture_default_str();
  sub->add_option("--report", args->report, "write residual plots before and after into this directory (HTML)");
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  // The workflow starts from the translation-only frame, so that a turn of the stitched frames shows up on the
  // held-out placements as the frame_rotation effect, named and sized, instead of being hidden by the model's.
  args->settings.stitched_frame = "translated";
  AddIdentifyOptions(*sub, args->settings);
  sub->footer("The stitched frame defaults to 'translated' here (not 'rotated' as in calibrate): the diagnosis starts from "
              "the plainest convention, so that a turn of each stitched export about its first tile is found and named "
              "(frame_rotation).\n"
              "Example:\n  fvm simulate fvm-batch -o drift --hidden-effect thermal_drift && fvm diagnose drift --model 27");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
