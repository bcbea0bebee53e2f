// fvm verify DATA.csv --chain XFYZ --order N --tool X,Y,Z [--fit-pose | --pose ...] -o MACHINE.json: volumetric
// verification of a machine tool from laser-tracker readings.

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <optional>

#include "artefacts/io/tracker_readings.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "artefacts/tracker_observations.h"
#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "fvm/commands.h"
#include "fvm/machine_problem.h"
#include "fvm/machine_report.h"
#include "fvm/option_parsing.h"
#include "stage/calibration.h"
#include "stage/error_terms.h"
#include "stage/io/calibration_file.h"
#include "stage/machine_verification.h"
#include "stage/tracker.h"

namespace fvm::cli {
namespace {

struct VerifyArgs : MachineArgs {
  std::string order = "3";
  std::string output;
  std::string report;
  bool json = false;
};

struct OrderFit {
  int order = 0;
  std::optional<stage::VerificationResult> result;
  double bic = 0;
  std::optional<stage::VolumetricError> validation_before, validation_after;
};

// Before (ideal machine, initial pose) and after (identified model and pose) volumetric error of each reading.
std::vector<MachineReportData::PointError> PointErrors(const stage::VerificationResult& v,
                                                       const std::vector<stage::Observation>& observations,
                                                       const std::vector<Eigen::Vector3d>& tools) {
  const stage::Calibration& cal = v.identified.calibration;
  const std::vector<Eigen::Vector3d> before =
      stage::VolumetricResiduals(cal.layout, nullptr, v.initial_pose, observations, tools);
  const std::vector<Eigen::Vector3d> after =
      stage::VolumetricResiduals(cal.layout, &cal.values, v.identified.pose, observations, tools);
  std::vector<MachineReportData::PointError> out;
  for (size_t i = 0; i < observations.size(); ++i) {
    const Eigen::Vector3d& q = observations[i].command;
    out.push_back({q.x(), q.y(), q.z(), before[i].norm() * 1e3, after[i].norm() * 1e3});
  }
  return out;
}

std::vector<std::string> Row(std::initializer_list<std::string> cells) { return cells; }

// The report's content: the error functions sampled over each axis' travel relative to the axis' origin, with
// u from the covariance; the tables; the errors of every point.
}  // namespace

MachineReportData MachineVerificationReport(const MachineArgs& args, const nlohmann::json& doc, const stage::VerificationResult& v,
                                            const std::vector<stage::Observation>& observations,
                                            const std::vector<stage::Observation>* validation,
                                            const std::vector<Eigen::Vector3d>& tools) {
  const stage::IdentificationResult& r = v.identified;
  const stage::Calibration& cal = r.calibration;
  MachineReportData data;
  data.title = fmt::format("fvm verify: {} order {} ({}) on {}", doc["chain"].get<std::string>(), doc["order"].get<int>(),
                           args.basis, args.data);
  const auto errors = [](const nlohmann::json& e) {
    return fmt::format("max {:.1f} / mean {:.1f} / min {:.1f} um", e["max_um"].get<double>(), e["mean_um"].get<double>(),
                       e["min_um"].get<double>());
  };
  data.summary = {{"points", fmt::format("{} ({} weights)", observations.size(), doc["weights"].get<std::string>())},
                  {"volumetric error, initial", errors(doc["initial"])},
                  {"volumetric error, final", errors(doc["final"])}};
  if (validation != nullptr) {
    data.summary.push_back({fmt::format("validation ({} points), initial", validation->size()), errors(doc["validation"]["initial"])});
    data.summary.push_back({"validation, final", errors(doc["validation"]["final"])});
  }
  data.summary.push_back({"free coefficients", fmt::format("{} ({} fixed)", cal.layout.NumFree(), r.fixed.size())});
  data.summary.push_back({"converged", r.converged ? "yes" : "no"});

  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = cal.layout.travel()[static_cast<size_t>(k)].min;
  constexpr int kSamples = 101;
  for (int k = 0; k < 3; ++k) {
    MachineReportData::AxisFunctions& f = data.functions[static_cast<size_t>(k)];
    f.axis = std::string(1, "XYZ"[k]);
    const stage::Travel travel = cal.layout.travel()[static_cast<size_t>(k)];
    const stage::Axis axis = static_cast<stage::Axis>(k);
    for (int c = 0; c < 3; ++c) {
      f.translations.push_back({std::string(stage::GetErrorTerm(stage::TranslationTerm(axis, c)).vdi), {}, {}});
      f.rotations.push_back({std::string(stage::GetErrorTerm(stage::RotationTerm(axis, c)).vdi), {}, {}});
    }
    for (int i = 0; i < kSamples; ++i) {
      Eigen::Vector3d q = origin;
      q[k] = travel.min + (travel.max - travel.min) * i / (kSamples - 1);
      f.position_mm.push_back(q[k]);
      const stage::TermValuesWithUncertainty t = stage::TermValuesAt(cal, q, &origin);
      for (int c = 0; c < 3; ++c) {
        const int tt = stage::TranslationTerm(axis, c), rt = stage::RotationTerm(axis, c);
        f.translations[static_cast<size_t>(c)].value.push_back(t.value[tt] * 1e3);
        f.translations[static_cast<size_t>(c)].u.push_back(t.u[tt] * 1e3);
        f.rotations[static_cast<size_t>(c)].value.push_back(t.value[rt] * 1e6);
        f.rotations[static_cast<size_t>(c)].u.push_back(t.u[rt] * 1e6);
      }
    }
  }

  MachineReportData::Table squareness{"Squareness", "Constant angles; U is the expanded uncertainty (k = 2).",
                                      {"term", "value (urad)", "U (urad)"}, {}};
  const stage::TermValuesWithUncertainty at_origin = stage::TermValuesAt(cal, origin);
  for (int w = 0; w < 3; ++w) {
    const int t = stage::kFirstSquarenessTerm + w;
    squareness.rows.push_back(Row({std::string(stage::GetErrorTerm(t).vdi), fmt::format("{:.2f}", at_origin.value[t] * 1e6),
                                   fmt::format("{:.2f}", 2 * at_origin.u[t] * 1e6)}));
  }
  data.tables.push_back(squareness);

  const nlohmann::json& p = doc["pose"];
  MachineReportData::Table pose{"Tracker pose",
                                fmt::format("{} in the machine frame; u is the standard uncertainty.",
                                            p["estimated"].get<bool>() ? "Estimated jointly with the errors" : "Held (--pose)"),
                                {"", "x", "y", "z"}, {}};
  const auto triple = [&](const char* what, const nlohmann::json& values, const char* format) {
    std::vector<std::string> row{what};
    for (int i = 0; i < 3; ++i) row.push_back(fmt::format(fmt::runtime(format), values[static_cast<size_t>(i)].get<double>()));
    pose.rows.push_back(row);
  };
  triple("translation (mm)", p["translation_mm"], "{:.4f}");
  if (p.contains("u_translation_um")) triple("u translation (um)", p["u_translation_um"], "{:.1f}");
  triple("XYZ Euler angles (deg)", p["euler_xyz_deg"], "{:.5f}");
  triple("rotation vector (rad)", p["rotation_vector_rad"], "{:.7f}");
  if (p.contains("u_rotation_urad")) triple("u rotation vector (urad)", p["u_rotation_urad"], "{:.1f}");
  data.tables.push_back(pose);

  MachineReportData::Table fixed{"Terms the data cannot separate",
                                 "Fixed at zero before the fit, each with the combination of other parameters that has the "
                                 "same effect on these readings (the pose absorbs constants; aliases share one effect).",
                                 {"coefficient", "reason"}, {}};
  for (const stage::FixedCoefficient& f : r.fixed) fixed.rows.push_back(Row({f.name, f.reason}));
  data.tables.push_back(fixed);

  data.readings = PointErrors(v, observations, tools);
  if (validation != nullptr) data.validation = PointErrors(v, *validation, tools);
  return data;
}

namespace {

void Run(const VerifyArgs& args) {
  const MachineProblem problem = LoadMachineProblem(args);
  const artefacts::TrackerReadings& readings = problem.readings;
  const std::optional<artefacts::TrackerReadings>& validation = problem.validation;
  const stage::AxisChain& chain = problem.chain;
  const stage::IdentificationOptions& options = problem.options;
  const stage::TrackerNoise& noise = problem.noise;
  const bool weighted = problem.weighted;
  const std::vector<stage::Observation>& observations = problem.observations;

  std::vector<int> orders;
  if (args.order == "auto") {
    orders = {1, 2, 3};
  } else {
    orders = {args.order[0] - '0'};  // 1, 2 or 3: the option's check allows no other
  }
  std::vector<OrderFit> fits;
  for (int order : orders) {
    OrderFit fit;
    fit.order = order;
    fit.result = VerifyProblem(problem, problem.Layout(order));
    const stage::IdentificationResult& r = fit.result->identified;
    // BIC [Schwarz 1978] on the (weighted) residuals: chi^2 + k ln(N), or N ln(RSS / N) + k ln(N) with equal weights.
    const double n_eq = 3.0 * static_cast<double>(observations.size());
    const double k = static_cast<double>(r.calibration.layout.NumFree() + (args.pose.empty() ? 6 : 0));
    const double dof = std::max(1.0, n_eq - k);
    const double fit_term = weighted ? r.weighted_rms * r.weighted_rms * dof
                                     : n_eq * std::log(std::max(r.rms_mm * r.rms_mm, 1e-30));
    fit.bic = fit_term + k * std::log(n_eq);
    if (validation) {
      const std::vector<stage::Observation>& others = problem.validation_observations;
      fit.validation_before = stage::SummarizeVolumetric(stage::VolumetricResiduals(
          r.calibration.layout, nullptr, fit.result->initial_pose, others, options.tool_offsets));
      fit.validation_after = stage::SummarizeVolumetric(stage::VolumetricResiduals(
          r.calibration.layout, &r.calibration.values, r.pose, others, options.tool_offsets));
    }
    fits.push_back(std::move(fit));
  }
  // --order auto: the order that predicts the held-out points best, or the lowest BIC without them.
  size_t best = 0;
  for (size_t i = 1; i < fits.size(); ++i) {
    const bool better = validation ? fits[i].validation_after->mean_um < fits[best].validation_after->mean_um
                                   : fits[i].bic < fits[best].bic;
    if (better) best = i;
  }
  const OrderFit& chosen = fits[best];
  const stage::VerificationResult& v = *chosen.result;
  const stage::IdentificationResult& r = v.identified;

  CheckTrackerSight(problem, r.pose);

  nlohmann::json doc;
  doc["data"] = args.data;
  doc["chain"] = chain.code;
  doc["basis"] = args.basis;
  doc["order"] = chosen.order;
  doc["points"] = readings.points.size();
  doc["weights"] = weighted ? "tracker " + noise.name : std::string("equal");
  doc["initial"] = ErrorJson(v.initial);
  doc["final"] = ErrorJson(v.final);
  doc["final"]["rms_um"] = r.rms_mm * 1e3;
  if (weighted) doc["final"]["weighted_rms"] = r.weighted_rms;
  if (validation) {
    doc["validation"] = {{"points", validation->points.size()},
                         {"initial", ErrorJson(*chosen.validation_before)},
                         {"final", ErrorJson(*chosen.validation_after)}};
  }
  doc["pose"] = PoseJson(r.pose, args.pose.empty() ? &r.pose_covariance : nullptr);
  doc["pose"]["estimated"] = args.pose.empty();
  doc["pose"]["initial"] = PoseJson(v.initial_pose, nullptr);
  const nlohmann::json calibration = stage::CalibrationToJson(r);
  doc["fixed"] = calibration["fixed"];
  doc["parameters"] = calibration["parameters"];
  doc["plausibility"] = PlausibilityJson(r, args.max_error_mm);
  doc["converged"] = r.converged;
  if (!r.converged) doc["solver_report"] = r.solver_report;
  if (fits.size() > 1) {
    for (const OrderFit& f : fits) {
      nlohmann::json o{{"order", f.order}, {"bic", f.bic}, {"final", ErrorJson(f.result->final)},
                       {"free", f.result->identified.calibration.layout.NumFree()}};
      if (f.validation_after) o["validation_final"] = ErrorJson(*f.validation_after);
      doc["orders"].push_back(o);
    }
    doc["order_chosen_by"] = validation ? "validation mean" : "BIC";
  }

  if (!args.report.empty()) {
    WriteMachineReport(args.report, MachineVerificationReport(args, doc, v, observations, validation ? &problem.validation_observations : nullptr,
                                             options.tool_offsets));
  }
  if (!args.output.empty()) {
    nlohmann::json model = calibration;
    model["model"] = fmt::format("machine {} {} order {}", chain.code, args.basis, chosen.order);
    model["instrument_pose"] = doc["pose"];
    model["verification"] = {{"data", args.data}, {"initial", doc["initial"]}, {"final", doc["final"]}};
    WriteFileAtomically(args.output, model.dump(2) + "\n");
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("verified {} {} points ({} weights), order {} {}{}:\n", readings.points.size(), chain.code,
               weighted ? "tracker " + noise.name : std::string("equal"), chosen.order, args.basis,
               fits.size() > 1 ? fmt::format(" (chosen by {})", validation ? "validation mean" : "BIC") : "");
    fmt::print("  volumetric error   initial max {:.1f} / mean {:.1f} / min {:.1f} um   final max {:.1f} / mean {:.1f} / min {:.1f} um\n",
               v.initial.max_um, v.initial.mean_um, v.initial.min_um, v.final.max_um, v.final.mean_um, v.final.min_um);
    if (validation) {
      fmt::print("  validation ({} points) initial mean {:.1f} um, final mean {:.1f} um (max {:.1f})\n", validation->points.size(),
                 chosen.validation_before->mean_um, chosen.validation_after->mean_um, chosen.validation_after->max_um);
    }
    const nlohmann::json& p = doc["pose"];
    fmt::print("  tracker pose ({}): {:.3f}, {:.3f}, {:.3f} mm; XYZ Euler {:.4f}, {:.4f}, {:.4f} deg\n",
               args.pose.empty() ? "estimated" : "held", p["translation_mm"][0].get<double>(), p["translation_mm"][1].get<double>(),
               p["translation_mm"][2].get<double>(), p["euler_xyz_deg"][0].get<double>(), p["euler_xyz_deg"][1].get<double>(),
               p["euler_xyz_deg"][2].get<double>());
    fmt::print("  {} coefficients free, {} fixed (see --json 'fixed' for each reason){}\n", r.calibration.layout.NumFree(),
               r.fixed.size(), args.output.empty() ? "" : "; model written to " + args.output);
  }
  if (!r.converged) throw NotConvergedError(NotConvergedReason(r));
}

}  // namespace

void RegisterVerify(CLI::App& app) {
  auto args = std::make_shared<VerifyArgs>();
  CLI::App* sub = app.add_subcommand("verify", "machine-tool volumetric verification from laser-tracker readings");
  AddDetails(sub,
             "Identifies the 21 geometric error functions of a three-axis machine (polynomials of --order in --basis) "
             "and the tracker pose from readings at commanded points, each weighted by the tracker's noise model "
             "(a 3x3 covariance per point). Volumetric error: distance between a reading and the model's prediction "
             "of the ideal machine (initial) or of the identified one (final), in the tracker frame. Error functions "
             "only matter up to their value at each axis' origin, which the tracker pose absorbs: the pose is "
             "estimated jointly unless --pose holds it, and terms the data cannot separate are fixed and named.");
  AddMachineOptions(sub, *args);
  sub->add_option("--order", args->order, "polynomial order of each error function, 1-3, or auto (held-out points or BIC)")
      ->check(CLI::IsMember({"1", "2", "3", "auto"}))
      ->capture_default_str();
  sub->add_option("-o,--output", args->output, "write the identified machine (calibration JSON with the tracker pose)");
  sub->add_option("--report", args->report,
                  "write an HTML report with SVG plots to this directory (error functions with 95 % bands, tracker "
                  "pose, fixed terms, volumetric errors and their map)");
  sub->add_flag("--json", args->json, "print the result as JSON");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --validation mesh:250,250,200 -o plan\n"
      "  fvm verify plan/readings.csv --chain XFYZ --order 3 --tool 0,0,100 --validate plan/validation.csv -o machine.json \\\n"
      "    --report machine-report");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
