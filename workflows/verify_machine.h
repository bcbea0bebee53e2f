#pragma once
// fvm verify as a job: the machine-tool volumetric verification of [IJSIMM 2016] from laser-tracker readings, at one
// polynomial order or the best of several (held-out points, or BIC [Schwarz 1978] without them).

#include <optional>
#include <string>
#include <vector>

#include "stage/machine_verification.h"
#include "workflows/machine_problem.h"

namespace fvm::workflows {

struct VerifyMachineOptions {
  MachineProblemOptions machine = {};  // the readings and how to read them (fvm verify's DATA, --chain, --tool, ...)
  std::vector<int> orders{3};     // polynomial orders (1-3) to try; with several the best one is chosen (--order auto)
  // The machine's options, and orders 1-3 only (--order).
  void Check() const;
};
// --order as the command line and Python spell it: "1", "2", "3" or "auto" (all three); InputError otherwise.
std::vector<int> ParseOrders(const std::string& text);

// One order identified, with what judges it.
struct OrderFit {
  int order = 0;
  stage::VerificationResult result;
  // [Schwarz 1978] on the (weighted) residuals: chi^2 + k ln(N), or N ln(RSS / N) + k ln(N) with equal weights; the
  // pose's 6 parameters count when estimated.
  double bic = 0;
  std::optional<VolumetricChange> validation;  // the held-out points, when the problem has them
};

struct MachineVerification {
  std::vector<OrderFit> fits;  // in the order of the options' orders
  size_t chosen = 0;           // the lowest validation mean error, or the lowest BIC without validation
  const OrderFit& Chosen() const { return fits[chosen]; }
  // "validation mean" or "BIC": what chose among several orders.
  std::string ChosenBy() const { return fits.front().validation ? "validation mean" : "BIC"; }
};

// Identifies every order; refusals as VerifyProblem's. Then refuses readings the tracker could not have made from
// the chosen fit's pose (CheckTrackerSight). A fit that did not converge is returned as it is (its `converged`).
MachineVerification VerifyMachine(const MachineProblem& problem, const VerifyMachineOptions& options);

}  // namespace fvm::workflows
