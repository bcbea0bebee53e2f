// fvm verify DATA.csv --chain XFYZ --order N --tool X,Y,Z [--fit-pose | --pose ...] -o MACHINE.json: volumetric
// verification of a machine tool from laser-tracker readings.

#include <fmt/core.h>

#include <optional>

#include "core/exit_codes.h"
#include "core/file_io.h"
#include "fvm/commands.h"
#include "fvm/machine_problem.h"
#include "report/machine_report.h"
#include "stage/io/calibration_file.h"
#include "workflows/verify_machine.h"

namespace fvm::cli {
namespace {

struct VerifyArgs : MachineArgs {
  std::string order = "3";
  std::string output;
  std::string report;
  bool json = false;
};

void Run(const VerifyArgs& args) {
  const MachineProblem problem = LoadMachineProblem(args);
  const artefacts::TrackerReadings& readings = problem.readings;
  const std::optional<artefacts::TrackerReadings>& validation = problem.validation;
  const stage::AxisChain& chain = problem.chain;
  const stage::IdentificationOptions& options = problem.options;
  const bool weighted = problem.weighted;
  const std::vector<stage::Observation>& observations = problem.observations;

  workflows::VerifyMachineOptions job;
  if (args.order == "auto") {
    job.orders = {1, 2, 3};
  } else {
    job.orders = {args.order[0] - '0'};  // 1, 2 or 3: the option's check allows no other
  }
  const workflows::MachineVerification verified = workflows::VerifyMachine(problem, job);
  const std::vector<workflows::OrderFit>& fits = verified.fits;
  const workflows::OrderFit& chosen = verified.Chosen();
  const stage::VerificationResult& v = chosen.result;
  const stage::IdentificationResult& r = v.identified;


  nlohmann::json doc;
  doc["data"] = args.data;
  doc["chain"] = chain.code;
  doc["basis"] = args.basis;
  doc["order"] = chosen.order;
  doc["points"] = readings.points.size();
  doc["weights"] = problem.WeightsName();
  doc["initial"] = ErrorJson(v.initial);
  doc["final"] = ErrorJson(v.final);
  doc["final"]["rms_um"] = r.residual_summary.rms_um();
  if (weighted) doc["final"]["weighted_rms"] = r.weighted_rms;
  if (validation) {
    doc["validation"] = {{"points", validation->points.size()},
                         {"initial", ErrorJson(chosen.validation->before)},
                         {"final", ErrorJson(chosen.validation->after)}};
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
    for (const workflows::OrderFit& f : fits) {
      nlohmann::json o{{"order", f.order}, {"bic", f.bic}, {"final", ErrorJson(f.result.final)},
                       {"free", f.result.identified.calibration.layout.NumFree()}};
      if (f.validation) o["validation_final"] = ErrorJson(f.validation->after);
      doc["orders"].push_back(o);
    }
    doc["order_chosen_by"] = verified.ChosenBy();
  }

  if (!args.report.empty()) {
    report::WriteMachineReport(args.report, MachineVerificationReport(args, doc, v, observations, validation ? &problem.validation_observations : nullptr,
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
               problem.WeightsName(), chosen.order, args.basis,
               fits.size() > 1 ? fmt::format(" (chosen by {})", verified.ChosenBy()) : "");
    fmt::print("  volumetric error   initial max {:.1f} / mean {:.1f} / min {:.1f} um   final max {:.1f} / mean {:.1f} / min {:.1f} um\n",
               v.initial.max_um(), v.initial.mean_um(), v.initial.min_um(), v.final.max_um(), v.final.mean_um(), v.final.min_um());
    if (validation) {
      fmt::print("  validation ({} points) initial mean {:.1f} um, final mean {:.1f} um (max {:.1f})\n", validation->points.size(),
                 chosen.validation->before.mean_um(), chosen.validation->after.mean_um(), chosen.validation->after.max_um());
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
             "(a 3x3 covariance per point), or by its own covariance where the readings carry one (cxx..czz, as "
             "fvm multilaterate --verify-readings writes). Volumetric error: distance between a reading and the model's prediction "
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
