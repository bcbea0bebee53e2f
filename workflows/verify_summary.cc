#include "workflows/verify_summary.h"

#include <fmt/core.h>

#include "stage/io/calibration_file.h"
#include "workflows/machine_summary.h"

namespace fvm::workflows {
namespace {

// The orders tried and what chose among them (--order auto).
void AddOrders(const MachineVerification& verified, nlohmann::json& doc) {
  if (verified.fits.size() < 2) return;
  for (const OrderFit& f : verified.fits) {
    nlohmann::json o{{"order", f.order}, {"bic", f.bic}, {"final", ErrorJson(f.result.final)},
                     {"free", f.result.identified.calibration.layout.NumFree()}};
    if (f.validation) o["validation_final"] = ErrorJson(f.validation->after);
    doc["orders"].push_back(o);
  }
  doc["order_chosen_by"] = verified.ChosenBy();
}

std::string Text(const MachineProblem& problem, const VerifyMachineOptions& options, const MachineVerification& verified,
                 const std::string& model_file) {
  const OrderFit& chosen = verified.Chosen();
  const stage::VerificationResult& v = chosen.result;
  const stage::IdentificationResult& r = v.identified;
  std::string text = fmt::format("verified {} {} points ({} weights), order {} {}{}:\n", problem.readings.points.size(),
                                 problem.chain.code, problem.WeightsName(), chosen.order, options.machine.basis,
                                 verified.fits.size() > 1 ? fmt::format(" (chosen by {})", verified.ChosenBy()) : "");
  text += fmt::format(
      "  volumetric error   initial max {:.1f} / mean {:.1f} / min {:.1f} um   final max {:.1f} / mean {:.1f} / min "
      "{:.1f} um\n",
      v.initial.max_um(), v.initial.mean_um(), v.initial.min_um(), v.final.max_um(), v.final.mean_um(), v.final.min_um());
  if (chosen.validation) {
    text += fmt::format("  validation ({} points) initial mean {:.1f} um, final mean {:.1f} um (max {:.1f})\n",
                        problem.validation->points.size(), chosen.validation->before.mean_um(),
                        chosen.validation->after.mean_um(), chosen.validation->after.max_um());
  }
  const Eigen::Vector3d e = EulerXyzDeg(r.pose);
  text += fmt::format("  tracker pose ({}): {:.3f}, {:.3f}, {:.3f} mm; XYZ Euler {:.4f}, {:.4f}, {:.4f} deg\n",
                      options.machine.pose ? "held" : "estimated", r.pose.translation.x(), r.pose.translation.y(),
                      r.pose.translation.z(), e.x(), e.y(), e.z());
  text += fmt::format("  {} coefficients free, {} fixed (see --json 'fixed' for each reason){}\n",
                      r.calibration.layout.NumFree(), r.fixed.size(),
                      model_file.empty() ? "" : "; model written to " + model_file);
  return text;
}

}  // namespace

Summary Summarize(const MachineProblem& problem, const VerifyMachineOptions& options,
                  const MachineVerification& verified, const std::string& model_file) {
  const OrderFit& chosen = verified.Chosen();
  Summary s;
  nlohmann::json doc = VerificationJson(problem, options.machine, chosen.order, chosen.result, chosen.validation);
  AddOrders(verified, doc);
  s.json = doc;  // sorted keys, as the command has always printed them
  s.text = Text(problem, options, verified, model_file);
  s.report = VerificationReport(fmt::format("fvm verify: {} order {} ({}) on {}", problem.chain.code, chosen.order,
                                            options.machine.basis, problem.readings.source),
                                problem.WeightsName(), problem, chosen.result, chosen.validation);
  return s;
}

nlohmann::json MachineModelJson(const MachineProblem& problem, const VerifyMachineOptions& options,
                                const MachineVerification& verified) {
  const OrderFit& chosen = verified.Chosen();
  const stage::VerificationResult& v = chosen.result;
  const stage::IdentificationResult& r = v.identified;
  nlohmann::json model = stage::CalibrationToJson(r);
  model["model"] = fmt::format("machine {} {} order {}", problem.chain.code, options.machine.basis, chosen.order);
  const bool held = options.machine.pose.has_value();
  model["instrument_pose"] = PoseJson(r.pose, held ? nullptr : &r.pose_covariance);
  model["instrument_pose"]["estimated"] = !held;
  model["instrument_pose"]["initial"] = PoseJson(v.initial_pose, nullptr);
  nlohmann::json final_error = ErrorJson(v.final);
  final_error["rms_um"] = r.residual_summary.rms_um();
  if (problem.weighted) final_error["weighted_rms"] = r.weighted_rms;
  model["verification"] = {{"initial", ErrorJson(v.initial)}, {"final", final_error}};
  return model;
}

}  // namespace fvm::workflows
