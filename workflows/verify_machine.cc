#include "workflows/verify_machine.h"

#include <algorithm>
#include <cmath>

#include <fmt/core.h>

namespace fvm::workflows {

void VerifyMachineOptions::Check() const {
  machine.Check();
  if (orders.empty()) throw InputError("--order: give an order 1, 2, 3 or auto");
  for (int order : orders) {
    if (order < 1 || order > 3) throw InputError(fmt::format("--order {}: use 1, 2, 3 or auto", order));
  }
}

std::vector<int> ParseOrders(const std::string& text) {
  if (text == "auto") return {1, 2, 3};
  if (text == "1" || text == "2" || text == "3") return {text[0] - '0'};
  throw InputError("--order " + text + ": use 1, 2, 3 or auto (the best of the three)");
}

MachineVerification VerifyMachine(const MachineProblem& problem, const VerifyMachineOptions& options) {
  if (options.orders.empty()) throw InputError("no polynomial order to verify: give one of 1, 2, 3");
  const bool estimate_pose = problem.options.instrument == stage::InstrumentPose::kEstimated;
  MachineVerification out;
  for (int order : options.orders) {
    OrderFit fit{order, VerifyProblem(problem, problem.Layout(order)), 0.0, std::nullopt};
    const stage::IdentificationResult& r = fit.result.identified;
    const double n_eq = 3.0 * static_cast<double>(problem.observations.size());
    const double k = static_cast<double>(r.calibration.layout.NumFree() + (estimate_pose ? 6 : 0));
    const double dof = std::max(1.0, n_eq - k);
    const double fit_term = problem.weighted ? r.weighted_rms * r.weighted_rms * dof
                                             : n_eq * std::log(std::max(r.residual_summary.rms_mm * r.residual_summary.rms_mm, 1e-30));
    fit.bic = fit_term + k * std::log(n_eq);
    if (problem.validation) {
      fit.validation = JudgeOn(fit.result, problem.validation_observations, problem.options.tool_offsets);
    }
    out.fits.push_back(std::move(fit));
  }
  for (size_t i = 1; i < out.fits.size(); ++i) {
    const OrderFit& a = out.fits[i];
    const OrderFit& best = out.fits[out.chosen];
    const bool better = a.validation ? a.validation->after.mean_um() < best.validation->after.mean_um() : a.bic < best.bic;
    if (better) out.chosen = i;
  }
  CheckTrackerSight(problem, out.Chosen().result.identified.pose);
  return out;
}

}  // namespace fvm::workflows
