#pragma once
// fvm uncertainty as two jobs, the Monte Carlo of an identification [GUM Supplement 1] with the [ISO/TS 15530-3]
// budget: a machine tool verified from tracker readings (the readings drawn again with the tracker's noise around
// the identified machine and pose, identified afresh), and the microscope stage calibrated from a batch (the
// stitched centres drawn again around the identified model). Each in two steps, the reference identification then
// the runs, so that a caller can show progress of the runs alone.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "stage/monte_carlo.h"
#include "stage/validation.h"
#include "workflows/machine_problem.h"
#include "workflows/model_choice.h"

namespace fvm::workflows {

struct MonteCarloSettings {
  int runs = 1000;
  std::uint64_t seed = 1;  // run i draws from a stream seeded by (seed, i): the same bits for any thread count
  int threads = 0;         // 0: all cores
  std::function<void()> on_run_done;  // after each run, from any thread (progress); may be empty
};

// ---------------------------------------------------------------------------------------------- machine tool

// The machine identified from the readings at `order`, taken as the truth of the runs.
struct MachineReference {
  stage::ParameterLayout layout;
  stage::VerificationResult verification;
};
// As fvm verify identifies (VerifyProblem, CheckTrackerSight); refuses a noise-free tracker (every run would be the
// same) as InputError, and throws NotConvergedError (core/exit_codes.h) when the reference did not converge.
MachineReference IdentifyMachineReference(const MachineProblem& problem, int order);

struct MachineUncertainty {
  std::vector<stage::MachineMonteCarloRun> runs;
  double seconds = 0;  // of the runs
  int converged = 0;
  std::vector<double> final_mean_um, validation_mean_um;  // one per run (validation: empty without it)
  // Pooled over runs and readings: the ideal machine's error (initial), the fit's residual (final), and the run's
  // model against the simulated truth (model error: what the published studies call the residual).
  std::vector<double> initial_pooled_um, final_pooled_um, model_error_pooled_um;
  std::vector<stage::PointSpread> spreads;  // the readings, then the validation readings
  stage::PairSpread pairs;                  // distance errors over pairs of the first 100 readings
  stage::UncertaintyBudget budget;
};
MachineUncertainty RunMachineMonteCarlo(const MachineProblem& problem, const MachineReference& reference,
                                        const MonteCarloSettings& settings, const stage::BudgetInputs& budget);

// ---------------------------------------------------------------------------------------------- microscope stage

struct StageUncertaintyOptions {
  std::string batch;              // batch directory (batch.json names its identify and validate placements)
  ModelChoice model;
  IdentifySettings settings;
  double centre_noise_um = -1.0;  // per coordinate of a stitched centre; < 0: the identification's residual sigma
};

struct StageReference {
  stage::MeasurementSet identify;
  std::optional<stage::MeasurementSet> validate;  // the batch's validation placements, when it names some
  stage::IdentificationResult identified;
  double sigma_mm = 0;  // the centre noise the runs draw
};
// Reads the batch and identifies the model as fvm calibrate does; throws NotConvergedError when it did not converge.
StageReference IdentifyStageReference(const StageUncertaintyOptions& options);

struct StageUncertainty {
  std::vector<stage::StageMonteCarloRun> runs;
  double seconds = 0;
  int converged = 0;
  std::vector<double> final_mean_um, validation_mean_um, validation_rms_um;  // one per run
  std::vector<stage::PointSpread> spreads;   // at the validation centres, or the identification's without them
  std::optional<stage::ValidationStats> validation;  // the reference's own validation, with its prediction
  stage::UncertaintyBudget budget;
};
StageUncertainty RunStageMonteCarlo(const StageUncertaintyOptions& options, const StageReference& reference,
                                    const MonteCarloSettings& settings, const stage::BudgetInputs& budget);

}  // namespace fvm::workflows
