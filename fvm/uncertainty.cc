// fvm uncertainty DATA.csv --chain XFYZ --order N --tool X,Y,Z --runs R --seed S [--validate VAL.csv] [--json]:
// Monte Carlo uncertainty of a machine-tool verification [GUM Supplement 1]: the readings are drawn again with the
// tracker's noise around the identified machine and identified afresh, R times.

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <nlohmann/json.hpp>

#include "core/exit_codes.h"
#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/identify_options.h"
#include "fvm/commands.h"
#include "fvm/machine_problem.h"
#include "fvm/option_parsing.h"
#include "report/uncertainty_report.h"
#include "stage/monte_carlo.h"
#include "workflows/tracker_placement.h"
#include "workflows/uncertainty.h"

namespace fvm::cli {
namespace {

struct UncertaintyArgs : MachineArgs {
  int order = 3;
  int runs = 1000;
  std::uint64_t seed = 1;
  double u_cal_um = 0.0;
  double temperature_c = 0.2;
  double cte_per_k = 11.5e-6;
  double k = 2.0;
  std::string report;
  bool json = false;
  // The microscope stage (DATA is a batch directory).
  workflows::ModelChoice model;
  double centre_noise_um = -1.0;  // < 0: the identification's residual standard deviation per coordinate
  workflows::IdentifySettings settings;
  // Tracker placement.
  std::string place_tracker;
  int place_steps = 4;
  int place_confirm = 3;
};

nlohmann::json DistributionJson(const stage::SampleSummary& s) {
  return {{"mean", s.mean}, {"sd", s.sd}, {"p2_5", s.p2_5}, {"p97_5", s.p97_5}, {"p95", s.p95}, {"max", s.max}};
}

stage::BudgetInputs BudgetInputsOf(const UncertaintyArgs& args) {
  stage::BudgetInputs inputs;
  inputs.u_cal_mm = args.u_cal_um * 1e-3;
  inputs.temperature_half_range_k = args.temperature_c;
  inputs.cte_per_k = args.cte_per_k;
  inputs.k = args.k;
  return inputs;
}

nlohmann::json BudgetJson(const stage::UncertaintyBudget& budget) {
  return {{"u_cal_um", budget.u_cal_mm * 1e3}, {"u_p_um", budget.u_p_mm * 1e3}, {"u_b_um", budget.u_b_mm * 1e3},
          {"u_w_um", budget.u_w_mm * 1e3},     {"U_um", budget.U_mm * 1e3},     {"k", budget.k},
          {"u_b_from", budget.repeated_commands > 0 ? "repeats" : "noise model"},
          {"length_mm", budget.length_mm}};
}

void PrintBudget(const stage::UncertaintyBudget& budget) {
  fmt::print("  budget (ISO/TS 15530-3): u_cal {:.2f}, u_p {:.2f}, u_b {:.2f} ({}), u_w {:.2f} um -> U = {:.2f} um (k = {})\n",
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

// The Monte Carlo settings of the command line; `progress` (may be null) advances with every run.
workflows::MonteCarloSettings MonteCarloSettingsOf(const UncertaintyArgs& args, Progress* progress) {
  workflows::MonteCarloSettings mc;
  mc.runs = args.runs;
  mc.seed = args.seed;
  mc.threads = Common().threads;
  if (progress != nullptr) mc.on_run_done = [progress] { progress->Advance(); };
  return mc;
}

report::UncertaintyReportData::Point ReportPoint(const std::string& id, const Eigen::Vector3d& q, const stage::PointSpread& s) {
  return {id, q.x(), q.y(), q.z(), s.u95_mm * 1e3,
          {s.semi_axes_mm[0] * 1e3, s.semi_axes_mm[1] * 1e3, s.semi_axes_mm[2] * 1e3},
          {s.covariance(0, 0) * 1e6, s.covariance(0, 1) * 1e6, s.covariance(1, 1) * 1e6}};
}

// fvm uncertainty BATCH --model 27: the microscope stage, its centre noise resampled.
void RunStage(const UncertaintyArgs& args) {
  if (!args.validate.empty() || !args.place_tracker.empty()) {
    throw InputError(fmt::format("{} is a batch directory: {} is for tracker readings (a batch names its validation "
                                 "placements in batch.json)",
                                 args.data, args.validate.empty() ? "--place-tracker" : "--validate"));
  }
  workflows::StageUncertaintyOptions job;
  job.batch = args.data;
  job.model = args.model;
  job.settings = Threaded(args.settings);
  job.centre_noise_um = args.centre_noise_um;
  const workflows::StageReference ref = workflows::IdentifyStageReference(job);
  const stage::MeasurementSet& identify = ref.identify;
  const std::optional<stage::MeasurementSet>& validate = ref.validate;
  const stage::IdentificationResult& reference = ref.identified;
  const double sigma_mm = ref.sigma_mm;

  Progress progress("monte carlo runs", args.runs, ShowProgress());
  const workflows::StageUncertainty u =
      workflows::RunStageMonteCarlo(job, ref, MonteCarloSettingsOf(args, &progress), BudgetInputsOf(args));
  progress.Finish();
  const double seconds = u.seconds;
  const std::vector<double>& finals = u.final_mean_um;
  const std::vector<double>& validation_means = u.validation_mean_um;
  const int converged = u.converged;
  const std::vector<stage::PointSpread>& spreads = u.spreads;
  const stage::UncertaintyBudget& budget = u.budget;

  nlohmann::json doc;
  doc["data"] = args.data;
  doc["model"] = reference.calibration.model;
  doc["runs"] = args.runs;
  doc["converged_runs"] = converged;
  doc["seed"] = args.seed;
  doc["seconds"] = seconds;
  doc["centre_noise_um"] = sigma_mm * 1e3;
  doc["final_mean_um"] = DistributionJson(stage::SummarizeSample(finals));
  doc["validation_mean_um"] = validate ? DistributionJson(stage::SummarizeSample(validation_means)) : nlohmann::json(nullptr);
  const std::optional<stage::ValidationStats>& stats = u.validation;
  if (validate) {
    doc["validation_rms_um"] = DistributionJson(stage::SummarizeSample(u.validation_rms_um));
    doc["reference"] = {{"validation_rms_um", stats->rms_mm * 1e3}, {"predicted_rms_um", stats->predicted_rms_mm * 1e3}};
  }
  nlohmann::json points = nlohmann::json::array();
  std::vector<double> u95s;
  AddPoints(spreads, 0, (validate ? *validate : identify).labels, validate ? "validation" : "identification", points, u95s);
  doc["points"] = points;
  const stage::SampleSummary u95 = stage::SummarizeSample(u95s);
  doc["U95_um"] = {{"mean", u95.mean}, {"max", u95.max}};
  doc["budget"] = BudgetJson(budget);
  if (!args.report.empty()) {
    report::UncertaintyReportData data;
    data.title = fmt::format("fvm uncertainty: model {}, {} runs, seed {} on {}", reference.calibration.model, args.runs,
                             args.seed, args.data);
    data.summary = {{"runs", fmt::format("{} ({} converged) in {:.1f} s", args.runs, converged, seconds)},
                    {"centre noise", fmt::format("{:.3f} um per coordinate", sigma_mm * 1e3)},
                    {"U95 per centre (um)", fmt::format("mean {:.3f}, max {:.3f}", u95.mean, u95.max)}};
    if (validate) {
      data.summary.push_back({"validation rms (um)", fmt::format("{:.3f} +- {:.3f}; predicted from the covariance {:.3f}",
                                                                 doc["validation_rms_um"]["mean"].get<double>(),
                                                                 doc["validation_rms_um"]["sd"].get<double>(),
                                                                 stats->predicted_rms_mm * 1e3)});
    }
    data.final_mean_um = finals;
    data.validation_mean_um = validation_means;
    const stage::MeasurementSet& evaluated = validate ? *validate : identify;
    for (size_t i = 0; i < spreads.size(); ++i) {
      const stage::PointSpread& p = spreads[i];
      const Eigen::Vector3d& q = evaluated.observations[i].command;
      data.points.push_back(ReportPoint(evaluated.labels[i], q, p));
    }
    report::WriteUncertaintyReport(args.report, data);
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("{} Monte Carlo runs of model {} on {} ({} centres, noise {:.3f} um per coordinate), seed {}: {:.1f} s, "
             "{} converged\n",
             args.runs, reference.calibration.model, args.data, identify.observations.size(), sigma_mm * 1e3, args.seed,
             seconds, converged);
  fmt::print("  identification mean error  {:.3f} +- {:.3f} um (the batch's own fit: {:.3f} um)\n",
             doc["final_mean_um"]["mean"].get<double>(), doc["final_mean_um"]["sd"].get<double>(), reference.residual_summary.mean_um());
  if (validate) {
    const nlohmann::json& v = doc["validation_rms_um"];
    fmt::print("  validation rms ({} centres)  {:.3f} +- {:.3f} um, 95 % of runs below {:.3f} um; the batch's {:.3f} um, "
               "predicted from the covariance {:.3f} um\n",
               validate->observations.size(), v["mean"].get<double>(), v["sd"].get<double>(), v["p95"].get<double>(),
               stats->rms_mm * 1e3, stats->predicted_rms_mm * 1e3);
  }
  fmt::print("  U95 of the predicted centre: mean {:.3f} um, max {:.3f} um\n", u95.mean, u95.max);
  PrintBudget(budget);
}

// --place-tracker X0,Y0,Z0,X1,Y1,Z1: workflows/tracker_placement.h.
void RunPlacement(const UncertaintyArgs& args, const MachineProblem& problem, const workflows::MachineReference& reference) {
  const std::vector<double> box = ParseNumbers(args.place_tracker, 6, "--place-tracker", "1000,-1500,0,2000,-500,800");
  workflows::TrackerPlacementOptions job;
  std::copy(box.begin(), box.end(), job.box.begin());
  job.box_name = "--place-tracker " + args.place_tracker;
  job.steps = args.place_steps;
  job.confirm = args.place_confirm;
  job.monte_carlo = MonteCarloSettingsOf(args, nullptr);
  Progress progress("tracker positions", workflows::PlacementPositions(job), ShowProgress());
  job.on_position_done = [&progress] { progress.Advance(); };
  const workflows::TrackerPlacement placed = workflows::PlaceTracker(problem, reference, job);
  const std::vector<workflows::PlacementCandidate>& ranked = placed.ranked;
  const double seconds = placed.seconds, propagation_seconds = placed.propagation_seconds;
  const size_t visible_in_box = placed.visible_in_box;

  nlohmann::json doc;
  doc["data"] = args.data;
  doc["box_mm"] = box;
  doc["candidates"] = placed.candidates;
  doc["visible"] = visible_in_box;
  doc["runs"] = args.runs;
  doc["seed"] = args.seed;
  doc["seconds"] = seconds;
  doc["propagation_seconds"] = propagation_seconds;
  nlohmann::json list = nlohmann::json::array();
  for (size_t r = 0; r < ranked.size(); ++r) {
    const workflows::PlacementCandidate& c = ranked[r];
    nlohmann::json e{{"rank", r + 1},
                     {"position_mm", {c.position.x(), c.position.y(), c.position.z()}},
                     {"predicted_max_U95_um", c.predicted_max_um},
                     {"current", c.current}};
    if (c.monte_carlo_max_um >= 0) e["monte_carlo_max_U95_um"] = c.monte_carlo_max_um;
    list.push_back(e);
  }
  doc["ranked"] = list;
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("{} tracker positions in the box ({} see every point), ranked by the largest 95 % radius over {} points "
             "(covariance propagation {:.1f} s; Monte Carlo {} runs each for the best {} and the current position; "
             "{:.1f} s in all)\n",
             placed.candidates, visible_in_box, problem.readings.points.size(), propagation_seconds, args.runs,
             args.place_confirm, seconds);
  fmt::print("  {:>4}  {:>28}  {:>14}  {:>14}\n", "rank", "position (mm)", "predicted (um)", "Monte Carlo");
  for (size_t r = 0; r < ranked.size(); ++r) {
    const workflows::PlacementCandidate& c = ranked[r];
    if (!(r < 10 || c.current || r + 1 == ranked.size())) continue;
    fmt::print("  {:>4}  {:>8.1f} {:>9.1f} {:>9.1f}  {:>14.2f}  {:>14}{}\n", r + 1, c.position.x(), c.position.y(),
               c.position.z(), c.predicted_max_um,
               c.monte_carlo_max_um >= 0 ? fmt::format("{:.2f}", c.monte_carlo_max_um) : std::string("-"),
               c.current ? "  (the readings' tracker)" : "");
  }
}

void Run(const UncertaintyArgs& args) {
  if (std::filesystem::is_directory(args.data)) {
    RunStage(args);
    return;
  }
  const MachineProblem problem = LoadMachineProblem(args);
  const workflows::MachineReference machine = workflows::IdentifyMachineReference(problem, args.order);
  const stage::VerificationResult& reference = machine.verification;

  if (!args.place_tracker.empty()) {
    RunPlacement(args, problem, machine);
    return;
  }

  Progress progress("monte carlo runs", args.runs, ShowProgress());
  const workflows::MachineUncertainty u =
      workflows::RunMachineMonteCarlo(problem, machine, MonteCarloSettingsOf(args, &progress), BudgetInputsOf(args));
  progress.Finish();
  const double seconds = u.seconds;
  const std::vector<double>& finals = u.final_mean_um;
  const std::vector<double>& validations = u.validation_mean_um;
  const int converged = u.converged;
  const std::vector<stage::PointSpread>& spreads = u.spreads;
  const stage::PairSpread& pairs = u.pairs;
  const stage::UncertaintyBudget& budget = u.budget;

  nlohmann::json doc;
  doc["data"] = args.data;
  doc["chain"] = problem.chain.code;
  doc["order"] = args.order;
  doc["runs"] = args.runs;
  doc["converged_runs"] = converged;
  doc["seed"] = args.seed;
  doc["seconds"] = seconds;
  doc["weights"] = problem.WeightsName();
  doc["final_mean_um"] = DistributionJson(stage::SummarizeSample(finals));
  doc["validation_mean_um"] = problem.validation ? DistributionJson(stage::SummarizeSample(validations)) : nlohmann::json(nullptr);
  doc["reference"] = {{"final_mean_um", reference.final.mean_um()}, {"initial_mean_um", reference.initial.mean_um()}};
  const stage::SampleSummary model_error = stage::SummarizeSample(u.model_error_pooled_um);
  doc["pooled_um"] = {{"initial", DistributionJson(stage::SummarizeSample(u.initial_pooled_um))},
                      {"final", DistributionJson(stage::SummarizeSample(u.final_pooled_um))},
                      {"model_error", DistributionJson(model_error)}};
  nlohmann::json points = nlohmann::json::array();
  std::vector<double> u95s;
  AddPoints(spreads, 0, IdsOf(problem.readings), "readings", points, u95s);
  if (problem.validation) AddPoints(spreads, problem.readings.points.size(), IdsOf(*problem.validation), "validation", points, u95s);
  doc["points"] = points;
  const stage::SampleSummary u95 = stage::SummarizeSample(u95s);
  doc["U95_um"] = {{"mean", u95.mean}, {"max", u95.max}};
  if (pairs.pairs > 0) {
    doc["pairs"] = {{"pairs", pairs.pairs},
                    {"U95_um", {{"mean", pairs.all_um.mean}, {"max", pairs.worst_u95_um}}},
                    {"worst", {problem.readings.points[static_cast<size_t>(pairs.worst_i)].id,
                               problem.readings.points[static_cast<size_t>(pairs.worst_j)].id}}};
  }
  doc["budget"] = BudgetJson(budget);

  if (!args.report.empty()) {
    report::UncertaintyReportData data;
    data.title = fmt::format("fvm uncertainty: {} order {}, {} runs, seed {} on {}", problem.chain.code, args.order, args.runs,
                             args.seed, args.data);
    data.summary = {{"runs", fmt::format("{} ({} converged) in {:.1f} s", args.runs, converged, seconds)},
                    {"final mean error (um)", fmt::format("{:.2f} +- {:.2f}", doc["final_mean_um"]["mean"].get<double>(),
                                                          doc["final_mean_um"]["sd"].get<double>())}};
    if (problem.validation) {
      data.summary.push_back({"validation mean error (um)",
                              fmt::format("{:.2f} +- {:.2f}", doc["validation_mean_um"]["mean"].get<double>(),
                                          doc["validation_mean_um"]["sd"].get<double>())});
    }
    data.summary.push_back({"U95 per point (um)", fmt::format("mean {:.2f}, max {:.2f}", u95.mean, u95.max)});
    data.summary.push_back({"budget", fmt::format("u_cal {:.2f}, u_p {:.2f}, u_b {:.2f}, u_w {:.2f} um; U = {:.2f} um (k = {})",
                                                  budget.u_cal_mm * 1e3, budget.u_p_mm * 1e3, budget.u_b_mm * 1e3,
                                                  budget.u_w_mm * 1e3, budget.U_mm * 1e3, budget.k)});
    data.final_mean_um = finals;
    data.validation_mean_um = validations;
    for (size_t i = 0; i < problem.observations.size(); ++i) {
      const stage::PointSpread& s = spreads[i];
      const Eigen::Vector3d& q = problem.observations[i].command;
      data.points.push_back(ReportPoint(problem.readings.points[i].id, q, s));
    }
    report::WriteUncertaintyReport(args.report, data);
  }

  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("{} Monte Carlo runs of {} {} points ({} weights), order {}, seed {}: {:.1f} s, {} converged\n", args.runs,
             problem.readings.points.size(), problem.chain.code, problem.WeightsName(), args.order, args.seed, seconds,
             converged);
  fmt::print("  final mean error       {:.2f} +- {:.2f} um (the readings' own fit: {:.2f} um)\n",
             doc["final_mean_um"]["mean"].get<double>(), doc["final_mean_um"]["sd"].get<double>(), reference.final.mean_um());
  if (problem.validation) {
    const auto& v = doc["validation_mean_um"];
    fmt::print("  validation mean error  {:.2f} +- {:.2f} um, 95 % of runs below {:.2f} um\n", v["mean"].get<double>(),
               v["sd"].get<double>(), v["p95"].get<double>());
  }
  fmt::print("  every point of every run: initial {:.2f} +- {:.2f} um, final {:.2f} +- {:.2f} um; model against the "
             "simulated truth {:.2f} +- {:.2f} um, 95 % below {:.2f} um, max {:.2f} um\n",
             doc["pooled_um"]["initial"]["mean"].get<double>(), doc["pooled_um"]["initial"]["sd"].get<double>(),
             doc["pooled_um"]["final"]["mean"].get<double>(), doc["pooled_um"]["final"]["sd"].get<double>(), model_error.mean,
             model_error.sd, model_error.p95, model_error.max);
  fmt::print("  U95 of the predicted point (radius holding 95 % of runs): mean {:.2f} um, max {:.2f} um\n", u95.mean, u95.max);
  if (pairs.pairs > 0) {
    fmt::print("  distance errors over {} pairs: U95 mean {:.2f} um, max {:.2f} um ({} - {})\n", pairs.pairs,
               pairs.all_um.mean, pairs.worst_u95_um, problem.readings.points[static_cast<size_t>(pairs.worst_i)].id,
               problem.readings.points[static_cast<size_t>(pairs.worst_j)].id);
  }
  PrintBudget(budget);
}

}  // namespace

void RegisterUncertainty(CLI::App& app) {
  auto args = std::make_shared<UncertaintyArgs>();
  CLI::App* sub = app.add_subcommand("uncertainty", "Monte Carlo uncertainty of a machine verification or stage calibration [GUM Supplement 1]");
  AddDetails(sub,
             "Identifies the machine from the readings as fvm verify does, takes that machine and tracker pose as the "
             "truth, and --runs times draws the readings again with the tracker's noise (normal in range, azimuth and "
             "elevation) and identifies them afresh. Reports the distribution of the final and validation mean errors "
             "over the runs, each point's 95 % radius and ellipsoid, distance errors over point pairs, and the "
             "[ISO/TS 15530-3] budget U = k sqrt(u_cal^2 + u_p^2 + u_b^2 + u_w^2). Run i draws from a stream seeded by "
             "(--seed, i): the same seed gives the same bits for any --threads. With a batch directory instead of "
             "readings, the microscope stage: the model (--model) is identified as fvm calibrate does, the stitched "
             "centres are drawn again around it with their noise, and the validation rms over the runs is shown next "
             "to the covariance-based prediction of fvm calibrate.");
  AddMachineOptions(sub, *args);
  sub->add_option("--order", args->order, "polynomial order of each error function")->check(Count(1, 3))->capture_default_str();
  sub->add_option("--runs", args->runs, "Monte Carlo runs")->check(Count(1, 100'000))->capture_default_str();
  sub->add_option("--seed", args->seed, "seed of the noise draws")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--u-cal-um", args->u_cal_um, "standard uncertainty of the reference's calibration (um)")
      ->check(Within(0.0, 1e3, "um"))->capture_default_str();
  sub->add_option("--temperature-c", args->temperature_c, "half-range of the temperature, rectangular (C)")
      ->check(Within(0.0, 50.0, "C"))->capture_default_str();
  sub->add_option("--cte-per-k", args->cte_per_k, "expansion coefficient of the workpiece (1/K; aluminium 24e-6)")
      ->check(Within(0.0, 1e-3, "1/K"))->capture_default_str();
  sub->add_option("--k", args->k, "coverage factor")->check(Within(0.5, 10.0))->capture_default_str();
  sub->add_option("--report", args->report, "write an HTML report with SVG plots and CSV tables to this directory");
  sub->add_option("--model", args->model.model, "microscope stage (DATA a batch): [Pérez 2019] model 9, 15, 27 or 42")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", args->model.terms, "microscope stage: your own model, TERM[:BASIS][:ORDER],... as in fvm calibrate");
  sub->add_option("--centre-noise-um", args->centre_noise_um,
                  "microscope stage: standard deviation of a stitched centre per coordinate (default: the fit's residual)")
      ->check(Within(0.0, 1e3, "um"));
  AddIdentifyOptions(*sub, args->settings);
  sub->add_option("--place-tracker", args->place_tracker,
                  "rank tracker positions on a grid of this box X0,Y0,Z0,X1,Y1,Z1 (machine frame, mm) by the largest "
                  "95 % radius over the points: covariance propagation for all, --runs Monte Carlo runs for the best")
      ->check(NumbersCheck(6, "--place-tracker", "1000,-1500,0,2000,-500,800"));
  sub->add_option("--place-steps", args->place_steps, "grid positions per axis of the --place-tracker box")
      ->check(Count(1, 50))->capture_default_str();
  sub->add_option("--place-confirm", args->place_confirm, "best positions the Monte Carlo confirms")
      ->check(Count(0, 100))->capture_default_str();
  sub->add_flag("--json", args->json, "print the result as JSON");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --validation mesh:250,250,200 -o plan\n"
      "  fvm uncertainty plan/readings.csv --chain XFYZ --order 3 --tool 0,0,100 --fit-pose --runs 1000 --seed 1 \\\n"
      "    --validate plan/validation.csv --json\n"
      "  fvm uncertainty samples/bar17 --model 27 --runs 200");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
