#include "workflows/uncertainty.h"

#include <chrono>
#include <cmath>

#include "artefacts/batch_observations.h"
#include "artefacts/io/batch.h"
#include "artefacts/tracker_observations.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "core/progress.h"

namespace fvm::workflows {
namespace {

stage::MonteCarloOptions OptionsOf(const MonteCarloSettings& settings, bool weighted) {
  stage::MonteCarloOptions mc;
  mc.runs = settings.runs;
  mc.seed = settings.seed;
  mc.threads = settings.threads;
  mc.weighted = weighted;
  mc.on_run_done = settings.on_run_done;
  return mc;
}

// One reading's 3D standard deviation (rms over the readings): from their own covariances, or the tracker's model.
double ReadingSd(const std::vector<stage::Observation>& readings, bool own, const stage::TrackerNoise& noise) {
  if (!own || readings.empty()) return stage::TrackerReadingSd(readings, noise);
  double trace = 0;
  for (const stage::Observation& o : readings) trace += o.covariance.trace();
  return std::sqrt(trace / static_cast<double>(readings.size()));
}

}  // namespace

MachineReference IdentifyMachineReference(const MachineProblem& problem, int order) {
  if (problem.noise.IsNoiseFree() && !artefacts::CarriesCovariances(problem.readings)) {
    throw InputError("--tracker none: a noise-free tracker gives every run the same readings; name the tracker's noise "
                     "(published, ifm, adm)");
  }
  const stage::ParameterLayout layout = problem.Layout(order);
  MachineReference reference{layout, VerifyProblem(problem, layout)};
  CheckTrackerSight(problem, reference.verification.identified.pose);
  if (!reference.verification.identified.converged) {
    throw NotConvergedError(NotConvergedReason(reference.verification.identified));
  }
  return reference;
}

MachineUncertainty RunMachineMonteCarlo(const MachineProblem& problem, const MachineReference& reference,
                                        const MonteCarloSettings& settings, const stage::BudgetInputs& budget) {
  MachineUncertainty u;
  const auto start = std::chrono::steady_clock::now();
  // Readings that carry their own covariances (multilaterated points) are drawn with those; the validation readings
  // likewise, so both are handed over with their covariances (own or the tracker's: the Monte Carlo reads them only
  // when they are their own). The problem's own observations carry none when the fit is unweighted.
  stage::MonteCarloOptions options = OptionsOf(settings, problem.weighted);
  options.readings_carry_covariances = artefacts::CarriesCovariances(problem.readings);
  const std::vector<stage::Observation> readings = options.readings_carry_covariances
                                                       ? artefacts::TrackerObservations(problem.readings, &problem.noise)
                                                       : problem.observations;
  std::vector<stage::Observation> validation;
  if (problem.validation) {
    validation = artefacts::TrackerObservations(*problem.validation, &problem.noise);
    options.validation_carries_covariances = artefacts::CarriesCovariances(*problem.validation);
  }
  u.runs = stage::MachineMonteCarlo(reference.layout, reference.verification, readings, validation, problem.noise,
                                    problem.options, options);
  u.seconds = SecondsSince(start);
  for (const stage::MachineMonteCarloRun& r : u.runs) {
    u.final_mean_um.push_back(r.final.mean_um());
    if (problem.validation) u.validation_mean_um.push_back(r.validation.mean_um());
    u.converged += r.converged ? 1 : 0;
  }
  for (const stage::MachineMonteCarloRun& r : u.runs) {
    u.initial_pooled_um.insert(u.initial_pooled_um.end(), r.initial_um.begin(), r.initial_um.end());
    u.final_pooled_um.insert(u.final_pooled_um.end(), r.final_um.begin(), r.final_um.end());
    for (size_t i = 0; i < problem.observations.size(); ++i) u.model_error_pooled_um.push_back(r.deviation_mm[i].norm() * 1e3);
  }
  u.spreads = stage::PointSpreads(u.runs);
  std::vector<Eigen::Vector3d> commands;
  for (const stage::Observation& o : problem.observations) commands.push_back(o.command);
  u.pairs = stage::PairDistanceSpread(u.runs, commands, 100);
  u.budget = stage::Budget(u.spreads, problem.observations, ReadingSd(readings, options.readings_carry_covariances, problem.noise),
                           budget);
  return u;
}

StageReference IdentifyStageReference(const StageUncertaintyOptions& options) {
  const artefacts::Batch batch = artefacts::ReadBatch(options.batch);
  stage::MeasurementSet identify = artefacts::Observations(batch, batch.identify);
  stage::IdentificationResult identified = IdentifyModel(options.model, identify, options.settings);
  StageReference r{std::move(identify), std::nullopt, std::move(identified), 0.0};
  if (!r.identified.converged) throw NotConvergedError(NotConvergedReason(r.identified));
  if (!batch.validate.empty()) r.validate = artefacts::Observations(batch, batch.validate);
  r.sigma_mm = options.centre_noise_um >= 0 ? options.centre_noise_um * 1e-3 : r.identified.calibration.sigma_mm;
  return r;
}

StageUncertainty RunStageMonteCarlo(const StageUncertaintyOptions& options, const StageReference& reference,
                                    const MonteCarloSettings& settings, const stage::BudgetInputs& budget) {
  StageUncertainty u;
  const std::optional<stage::MeasurementSet>& validate = reference.validate;
  const auto start = std::chrono::steady_clock::now();
  u.runs = stage::StageMonteCarlo(options.model.Layout(), reference.identified, reference.identify,
                                  validate ? &*validate : nullptr, reference.sigma_mm,
                                  options.settings.ToOptions(reference.identify), OptionsOf(settings, false));
  u.seconds = SecondsSince(start);
  for (const stage::StageMonteCarloRun& r : u.runs) {
    u.final_mean_um.push_back(r.fit_mean_mm * 1e3);
    if (validate) u.validation_mean_um.push_back(r.validation.mean_mm * 1e3), u.validation_rms_um.push_back(r.validation.rms_mm * 1e3);
    u.converged += r.converged ? 1 : 0;
  }
  u.spreads = stage::PointSpreads(u.runs);
  u.budget = stage::Budget(u.spreads, reference.identify.observations, std::sqrt(3.0) * reference.sigma_mm, budget);
  if (validate) {
    u.validation = stage::Validate(&reference.identified.calibration, validate->observations, validate->anchors,
                                   options.settings.Frame());
  }
  return u;
}

}  // namespace fvm::workflows
