#include "workflows/uncertainty_summary.h"

#include <fmt/core.h>

#include "core/input_error.h"

namespace fvm::workflows {
namespace {

nlohmann::json DistributionJson(const stage::SampleSummary& s) {
  return {{"mean", s.mean}, {"sd", s.sd}, {"p2_5", s.p2_5}, {"p97_5", s.p97_5}, {"p95", s.p95}, {"max", s.max}};
}

nlohmann::json BudgetJson(const stage::UncertaintyBudget& budget) {
  return {{"u_cal_um", budget.u_cal_mm * 1e3}, {"u_p_um", budget.u_p_mm * 1e3}, {"u_b_um", budget.u_b_mm * 1e3},
          {"u_w_um", budget.u_w_mm * 1e3},     {"U_um", budget.U_mm * 1e3},     {"k", budget.k},
          {"u_b_from", budget.repeated_commands > 0 ? "repeats" : "noise model"},
          {"length_mm", budget.length_mm}};
}

std::string BudgetText(const stage::UncertaintyBudget& budget) {
  return fmt::format("  budget (ISO/TS 15530-3): u_cal {:.2f}, u_p {:.2f}, u_b {:.2f} ({}), u_w {:.2f} um -> U = {:.2f} um (k = {})\n",
                     budget.u_cal_mm * 1e3, budget.u_p_mm * 1e3, budget.u_b_mm * 1e3,
                     budget.repeated_commands > 0 ? "repeats" : "noise model", budget.u_w_mm * 1e3, budget.U_mm * 1e3, budget.k);
}

// One entry per evaluation point: its id, 95 % radius and ellipsoid, and the mean deviation (the bias of
// re-identification), appended to `points`; the radii to `u95s`.
void AddPoints(const std::vector<stage::PointSpread>& spreads, size_t offset, const std::vector<std::string>& ids,
               const char* set, nlohmann::json& points, std::vector<double>& u95s) {
  for (size_t i = 0; i < ids.size(); ++i) {
    const stage::PointSpread& s = spreads[offset + i];
    u95s.push_back(s.u95_mm * 1e3);
    points.push_back({{"id", ids[i]},
                      {"set", set},
                      {"U95_um", s.u95_mm * 1e3},
                      {"ellipsoid_semi_axes_um", {s.semi_axes_mm[0] * 1e3, s.semi_axes_mm[1] * 1e3, s.semi_axes_mm[2] * 1e3}},
                      {"bias_um", s.mean_mm.norm() * 1e3}});
  }
}

std::vector<std::string> IdsOf(const artefacts::TrackerReadings& readings) {
  std::vector<std::string> ids;
  for (const artefacts::TrackerReading& r : readings.points) ids.push_back(r.id);
  return ids;
}

report::UncertaintyReportData::Point ReportPoint(const std::string& id, const Eigen::Vector3d& q, const stage::PointSpread& s) {
  return {id, q.x(), q.y(), q.z(), s.u95_mm * 1e3,
          {s.semi_axes_mm[0] * 1e3, s.semi_axes_mm[1] * 1e3, s.semi_axes_mm[2] * 1e3},
          {s.covariance(0, 0) * 1e6, s.covariance(0, 1) * 1e6, s.covariance(1, 1) * 1e6}};
}

std::string BudgetLine(const stage::UncertaintyBudget& budget) {
  return fmt::format("u_cal {:.2f}, u_p {:.2f}, u_b {:.2f}, u_w {:.2f} um; U = {:.2f} um (k = {})", budget.u_cal_mm * 1e3,
                     budget.u_p_mm * 1e3, budget.u_b_mm * 1e3, budget.u_w_mm * 1e3, budget.U_mm * 1e3, budget.k);
}

// ---------------------------------------------------------------------------------------------- machine tool

nlohmann::json MachineJson(const MachineProblem& problem, const UncertaintyOptions& o, const MachineReference& reference,
                           const MachineUncertainty& u) {
  const stage::VerificationResult& ref = reference.verification;
  nlohmann::json doc;
  doc["chain"] = problem.chain.code;
  doc["order"] = o.order;
  doc["runs"] = o.monte_carlo.runs;
  doc["converged_runs"] = u.converged;
  doc["seed"] = o.monte_carlo.seed;
  doc["seconds"] = u.seconds;
  doc["weights"] = problem.WeightsName();
  doc["final_mean_um"] = DistributionJson(stage::SummarizeSample(u.final_mean_um));
  doc["validation_mean_um"] =
      problem.validation ? DistributionJson(stage::SummarizeSample(u.validation_mean_um)) : nlohmann::json(nullptr);
  doc["reference"] = {{"final_mean_um", ref.final.mean_um()}, {"initial_mean_um", ref.initial.mean_um()}};
  doc["pooled_um"] = {{"initial", DistributionJson(stage::SummarizeSample(u.initial_pooled_um))},
                      {"final", DistributionJson(stage::SummarizeSample(u.final_pooled_um))},
                      {"model_error", DistributionJson(stage::SummarizeSample(u.model_error_pooled_um))}};
  nlohmann::json points = nlohmann::json::array();
  std::vector<double> u95s;
  AddPoints(u.spreads, 0, IdsOf(problem.readings), "readings", points, u95s);
  if (problem.validation) AddPoints(u.spreads, problem.readings.points.size(), IdsOf(*problem.validation), "validation", points, u95s);
  doc["points"] = points;
  const stage::SampleSummary u95 = stage::SummarizeSample(u95s);
  doc["U95_um"] = {{"mean", u95.mean}, {"max", u95.max}};
  if (u.pairs.pairs > 0) {
    doc["pairs"] = {{"pairs", u.pairs.pairs},
                    {"U95_um", {{"mean", u.pairs.all_um.mean}, {"max", u.pairs.worst_u95_um}}},
                    {"worst", {problem.readings.points[static_cast<size_t>(u.pairs.worst_i)].id,
                               problem.readings.points[static_cast<size_t>(u.pairs.worst_j)].id}}};
  }
  doc["budget"] = BudgetJson(u.budget);
  return doc;
}

// The 95 % radius of every point of the readings and the validation readings.
stage::SampleSummary U95Of(const std::vector<stage::PointSpread>& spreads) {
  std::vector<double> u95s;
  for (const stage::PointSpread& s : spreads) u95s.push_back(s.u95_mm * 1e3);
  return stage::SummarizeSample(u95s);
}

std::string MachineText(const MachineProblem& problem, const UncertaintyOptions& o, const MachineReference& reference,
                        const MachineUncertainty& u) {
  const stage::SampleSummary finals = stage::SummarizeSample(u.final_mean_um);
  const stage::SampleSummary initial = stage::SummarizeSample(u.initial_pooled_um);
  const stage::SampleSummary final_pooled = stage::SummarizeSample(u.final_pooled_um);
  const stage::SampleSummary model_error = stage::SummarizeSample(u.model_error_pooled_um);
  const stage::SampleSummary u95 = U95Of(u.spreads);
  std::string text = fmt::format("{} Monte Carlo runs of {} {} points ({} weights), order {}, seed {}: {:.1f} s, {} converged\n",
                                 o.monte_carlo.runs, problem.readings.points.size(), problem.chain.code,
                                 problem.WeightsName(), o.order, o.monte_carlo.seed, u.seconds, u.converged);
  text += fmt::format("  final mean error       {:.2f} +- {:.2f} um (the readings' own fit: {:.2f} um)\n", finals.mean,
                      finals.sd, reference.verification.final.mean_um());
  if (problem.validation) {
    const stage::SampleSummary v = stage::SummarizeSample(u.validation_mean_um);
    text += fmt::format("  validation mean error  {:.2f} +- {:.2f} um, 95 % of runs below {:.2f} um\n", v.mean, v.sd, v.p95);
  }
  text += fmt::format("  every point of every run: initial {:.2f} +- {:.2f} um, final {:.2f} +- {:.2f} um; model against the "
                      "simulated truth {:.2f} +- {:.2f} um, 95 % below {:.2f} um, max {:.2f} um\n",
                      initial.mean, initial.sd, final_pooled.mean, final_pooled.sd, model_error.mean, model_error.sd,
                      model_error.p95, model_error.max);
  text += fmt::format("  U95 of the predicted point (radius holding 95 % of runs): mean {:.2f} um, max {:.2f} um\n", u95.mean, u95.max);
  if (u.pairs.pairs > 0) {
    text += fmt::format("  distance errors over {} pairs: U95 mean {:.2f} um, max {:.2f} um ({} - {})\n", u.pairs.pairs,
                        u.pairs.all_um.mean, u.pairs.worst_u95_um, problem.readings.points[static_cast<size_t>(u.pairs.worst_i)].id,
                        problem.readings.points[static_cast<size_t>(u.pairs.worst_j)].id);
  }
  return text + BudgetText(u.budget);
}

report::UncertaintyReportData MachineReport(const MachineProblem& problem, const UncertaintyOptions& o,
                                            const MachineUncertainty& u) {
  const stage::SampleSummary finals = stage::SummarizeSample(u.final_mean_um);
  const stage::SampleSummary u95 = U95Of(u.spreads);
  report::UncertaintyReportData data;
  data.title = fmt::format("fvm uncertainty: {} order {}, {} runs, seed {} on {}", problem.chain.code, o.order,
                           o.monte_carlo.runs, o.monte_carlo.seed, problem.readings.source);
  data.summary = {{"runs", fmt::format("{} ({} converged) in {:.1f} s", o.monte_carlo.runs, u.converged, u.seconds)},
                  {"final mean error (um)", fmt::format("{:.2f} +- {:.2f}", finals.mean, finals.sd)}};
  if (problem.validation) {
    const stage::SampleSummary v = stage::SummarizeSample(u.validation_mean_um);
    data.summary.push_back({"validation mean error (um)", fmt::format("{:.2f} +- {:.2f}", v.mean, v.sd)});
  }
  data.summary.push_back({"U95 per point (um)", fmt::format("mean {:.2f}, max {:.2f}", u95.mean, u95.max)});
  data.summary.push_back({"budget", BudgetLine(u.budget)});
  data.final_mean_um = u.final_mean_um;
  data.validation_mean_um = u.validation_mean_um;
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    data.points.push_back(ReportPoint(problem.readings.points[i].id, problem.observations[i].command, u.spreads[i]));
  }
  return data;
}

// ---------------------------------------------------------------------------------------------- microscope stage

nlohmann::json StageJson(const UncertaintyOptions& o, const StageReference& ref, const StageUncertainty& u) {
  const bool validate = ref.validate.has_value();
  nlohmann::json doc;
  doc["model"] = ref.identified.calibration.model;
  doc["runs"] = o.monte_carlo.runs;
  doc["converged_runs"] = u.converged;
  doc["seed"] = o.monte_carlo.seed;
  doc["seconds"] = u.seconds;
  doc["centre_noise_um"] = ref.sigma_mm * 1e3;
  doc["final_mean_um"] = DistributionJson(stage::SummarizeSample(u.final_mean_um));
  doc["validation_mean_um"] = validate ? DistributionJson(stage::SummarizeSample(u.validation_mean_um)) : nlohmann::json(nullptr);
  if (validate) {
    doc["validation_rms_um"] = DistributionJson(stage::SummarizeSample(u.validation_rms_um));
    doc["reference"] = {{"validation_rms_um", u.validation->rms_mm * 1e3},
                        {"predicted_rms_um", u.validation->predicted_rms_mm * 1e3}};
  }
  nlohmann::json points = nlohmann::json::array();
  std::vector<double> u95s;
  AddPoints(u.spreads, 0, (validate ? *ref.validate : ref.identify).labels, validate ? "validation" : "identification",
            points, u95s);
  doc["points"] = points;
  const stage::SampleSummary u95 = stage::SummarizeSample(u95s);
  doc["U95_um"] = {{"mean", u95.mean}, {"max", u95.max}};
  doc["budget"] = BudgetJson(u.budget);
  return doc;
}

std::string StageText(const UncertaintyOptions& o, const StageReference& ref, const StageUncertainty& u) {
  const stage::SampleSummary finals = stage::SummarizeSample(u.final_mean_um);
  const stage::SampleSummary u95 = U95Of(u.spreads);
  std::string text = fmt::format("{} Monte Carlo runs of model {} on {} ({} centres, noise {:.3f} um per coordinate), seed {}: {:.1f} s, "
                                 "{} converged\n",
                                 o.monte_carlo.runs, ref.identified.calibration.model, o.stage.batch,
                                 ref.identify.observations.size(), ref.sigma_mm * 1e3, o.monte_carlo.seed, u.seconds, u.converged);
  text += fmt::format("  identification mean error  {:.3f} +- {:.3f} um (the batch's own fit: {:.3f} um)\n", finals.mean,
                      finals.sd, ref.identified.residual_summary.mean_um());
  if (ref.validate) {
    const stage::SampleSummary v = stage::SummarizeSample(u.validation_rms_um);
    text += fmt::format("  validation rms ({} centres)  {:.3f} +- {:.3f} um, 95 % of runs below {:.3f} um; the batch's {:.3f} um, "
                        "predicted from the covariance {:.3f} um\n",
                        ref.validate->observations.size(), v.mean, v.sd, v.p95, u.validation->rms_mm * 1e3,
                        u.validation->predicted_rms_mm * 1e3);
  }
  text += fmt::format("  U95 of the predicted centre: mean {:.3f} um, max {:.3f} um\n", u95.mean, u95.max);
  return text + BudgetText(u.budget);
}

report::UncertaintyReportData StageReport(const UncertaintyOptions& o, const StageReference& ref, const StageUncertainty& u) {
  const stage::SampleSummary u95 = U95Of(u.spreads);
  report::UncertaintyReportData data;
  data.title = fmt::format("fvm uncertainty: model {}, {} runs, seed {} on {}", ref.identified.calibration.model,
                           o.monte_carlo.runs, o.monte_carlo.seed, o.stage.batch);
  data.summary = {{"runs", fmt::format("{} ({} converged) in {:.1f} s", o.monte_carlo.runs, u.converged, u.seconds)},
                  {"centre noise", fmt::format("{:.3f} um per coordinate", ref.sigma_mm * 1e3)},
                  {"U95 per centre (um)", fmt::format("mean {:.3f}, max {:.3f}", u95.mean, u95.max)}};
  if (ref.validate) {
    const stage::SampleSummary v = stage::SummarizeSample(u.validation_rms_um);
    data.summary.push_back({"validation rms (um)", fmt::format("{:.3f} +- {:.3f}; predicted from the covariance {:.3f}",
                                                               v.mean, v.sd, u.validation->predicted_rms_mm * 1e3)});
  }
  data.final_mean_um = u.final_mean_um;
  data.validation_mean_um = u.validation_mean_um;
  const stage::MeasurementSet& evaluated = ref.validate ? *ref.validate : ref.identify;
  for (size_t i = 0; i < u.spreads.size(); ++i) {
    data.points.push_back(ReportPoint(evaluated.labels[i], evaluated.observations[i].command, u.spreads[i]));
  }
  return data;
}

// ---------------------------------------------------------------------------------------------- tracker placement

nlohmann::json PlacementJson(const UncertaintyOptions& o, const TrackerPlacement& placed) {
  nlohmann::json doc;
  doc["box_mm"] = *o.place_tracker;
  doc["candidates"] = placed.candidates;
  doc["visible"] = placed.visible_in_box;
  doc["runs"] = o.monte_carlo.runs;
  doc["seed"] = o.monte_carlo.seed;
  doc["seconds"] = placed.seconds;
  doc["propagation_seconds"] = placed.propagation_seconds;
  nlohmann::json list = nlohmann::json::array();
  for (size_t r = 0; r < placed.ranked.size(); ++r) {
    const PlacementCandidate& c = placed.ranked[r];
    nlohmann::json e{{"rank", r + 1},
                     {"position_mm", {c.position.x(), c.position.y(), c.position.z()}},
                     {"predicted_max_U95_um", c.predicted_max_um},
                     {"current", c.current}};
    if (c.monte_carlo_max_um >= 0) e["monte_carlo_max_U95_um"] = c.monte_carlo_max_um;
    list.push_back(e);
  }
  doc["ranked"] = list;
  return doc;
}

std::string PlacementText(const MachineProblem& problem, const UncertaintyOptions& o, const TrackerPlacement& placed) {
  std::string text = fmt::format(
      "{} tracker positions in the box ({} see every point), ranked by the largest 95 % radius over {} points "
      "(covariance propagation {:.1f} s; Monte Carlo {} runs each for the best {} and the current position; "
      "{:.1f} s in all)\n",
      placed.candidates, placed.visible_in_box, problem.readings.points.size(), placed.propagation_seconds,
      o.monte_carlo.runs, o.place_confirm, placed.seconds);
  text += fmt::format("  {:>4}  {:>28}  {:>14}  {:>14}\n", "rank", "position (mm)", "predicted (um)", "Monte Carlo");
  for (size_t r = 0; r < placed.ranked.size(); ++r) {
    const PlacementCandidate& c = placed.ranked[r];
    if (!(r < 10 || c.current || r + 1 == placed.ranked.size())) continue;
    text += fmt::format("  {:>4}  {:>8.1f} {:>9.1f} {:>9.1f}  {:>14.2f}  {:>14}{}\n", r + 1, c.position.x(), c.position.y(),
                        c.position.z(), c.predicted_max_um,
                        c.monte_carlo_max_um >= 0 ? fmt::format("{:.2f}", c.monte_carlo_max_um) : std::string("-"),
                        c.current ? "  (the readings' tracker)" : "");
  }
  return text;
}

}  // namespace

stage::BudgetInputs UncertaintyOptions::Budget() const {
  stage::BudgetInputs inputs;
  inputs.u_cal_mm = u_cal_um * 1e-3;
  inputs.temperature_half_range_k = temperature_c;
  inputs.cte_per_k = cte_per_k;
  inputs.k = k;
  return inputs;
}

TrackerPlacementOptions UncertaintyOptions::Placement() const {
  TrackerPlacementOptions job;
  if (place_tracker) job.box = *place_tracker;
  job.box_name = place_tracker_name;
  job.steps = place_steps;
  job.confirm = place_confirm;
  job.monte_carlo = monte_carlo;
  job.monte_carlo.on_run_done = nullptr;
  return job;
}

void UncertaintyOptions::Check() const {
  machine.Check();
  if (order < 1 || order > 3) throw InputError(fmt::format("--order {}: use 1, 2 or 3", order));
  if (monte_carlo.runs < 1) throw InputError(fmt::format("--runs {}: give 1 or more", monte_carlo.runs));
  if (!(u_cal_um >= 0)) throw InputError(fmt::format("--u-cal-um {}: give 0 or more", u_cal_um));
  if (!(temperature_c >= 0)) throw InputError(fmt::format("--temperature-c {}: give 0 or more", temperature_c));
  if (!(cte_per_k >= 0)) throw InputError(fmt::format("--cte-per-k {}: give 0 or more", cte_per_k));
  if (!(k > 0)) throw InputError(fmt::format("--k {}: give a coverage factor > 0", k));
  if (place_steps < 1) throw InputError(fmt::format("--place-steps {}: give 1 or more", place_steps));
  if (place_confirm < 0) throw InputError(fmt::format("--place-confirm {}: give 0 or more", place_confirm));
}

Summary Summarize(const MachineProblem& problem, const UncertaintyOptions& options, const MachineReference& reference,
                  const MachineUncertainty& u) {
  return {MachineJson(problem, options, reference, u), MachineText(problem, options, reference, u),
          MachineReport(problem, options, u)};
}

Summary Summarize(const UncertaintyOptions& options, const StageReference& reference, const StageUncertainty& u) {
  return {StageJson(options, reference, u), StageText(options, reference, u), StageReport(options, reference, u)};
}

Summary Summarize(const MachineProblem& problem, const UncertaintyOptions& options, const TrackerPlacement& placed) {
  return {PlacementJson(options, placed), PlacementText(problem, options, placed), std::nullopt};
}

}  // namespace fvm::workflows
