#pragma once
// fvm uncertainty's options (one struct for its three jobs: the machine tool's Monte Carlo, the microscope stage's,
// and the tracker placement) and what each tells its user (workflows/summary.h): the --json document, the printed
// lines and the report's data.

#include <array>
#include <optional>
#include <string>

#include "workflows/summary.h"
#include "workflows/tracker_placement.h"
#include "workflows/uncertainty.h"

namespace fvm::workflows {

struct UncertaintyOptions {
  MachineProblemOptions machine;   // DATA tracker readings (a batch directory: `stage` instead), --chain, --tool, ...
  int order = 3;                   // polynomial order of each error function
  MonteCarloSettings monte_carlo;  // --runs, --seed (threads: the program's)
  double u_cal_um = 0.0;           // standard uncertainty of the reference's calibration
  double temperature_c = 0.2;      // half-range of the temperature, rectangular
  double cte_per_k = 11.5e-6;      // expansion coefficient of the workpiece
  double k = 2.0;                  // coverage factor
  StageUncertaintyOptions stage;   // DATA a batch directory: --model, --terms, --centre-noise-um, identification
  std::optional<std::array<double, 6>> place_tracker;  // rank tracker positions in this box X0,Y0,Z0,X1,Y1,Z1 (mm)
  std::string place_tracker_name;  // how the box was given ("--place-tracker 1000,..."), first in its refusal
  int place_steps = 4;             // grid positions per axis of the box
  int place_confirm = 3;           // best positions the Monte Carlo confirms

  stage::BudgetInputs Budget() const;
  TrackerPlacementOptions Placement() const;
  // Names the option (--order, --runs, --k, ...) a value no job takes; the machine's options as MachineProblemOptions.
  void Check() const;
};

Summary Summarize(const MachineProblem& problem, const UncertaintyOptions& options, const MachineReference& reference,
                  const MachineUncertainty& u);
Summary Summarize(const UncertaintyOptions& options, const StageReference& reference, const StageUncertainty& u);
// The ranked positions (no report).
Summary Summarize(const MachineProblem& problem, const UncertaintyOptions& options, const TrackerPlacement& placed);

}  // namespace fvm::workflows
