#pragma once
// Monte Carlo uncertainty of an identification ([GUM Supplement 1]; [Pérez 2017], [Aguado 2017], [Pérez 2019 Sensors]),
// for a machine tool measured by a laser tracker and for the microscope stage. Machine: the truth is the identified
// machine and tracker pose plus the part of the machine its polynomials cannot follow, the readings' residuals shrunk
// by the share their noise explains (stage/residual_field.h; the validation readings' likewise, less the model's own
// estimation error too). The tracker's readings of it are drawn again and again with the tracker's noise (normal in
// range, azimuth and elevation, [IJSIMM 2016] eqs. 22-24), or each reading's own covariance when the readings carry
// one, and each set is identified afresh, rank treatment included, exactly as the original readings were, and judged
// on validation readings drawn afresh too. The spread of what the runs predict is the uncertainty of the verification;
// their validation errors are what a repeat measurement of the machine would show.
//
// Reproducible: run i draws from Random(StreamSeed(seed, i)) (core/random.h) and writes only its own result, and
// each identification runs on one thread, so the results are the same bits for any thread count.
//
// Stage: the identified stage model is the truth, the stitched centres are drawn again around what it predicts
// (normal, isotropic, the centres' noise) and identified afresh with the same anchoring.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "stage/tracker.h"
#include "stage/validation.h"

namespace fvm::stage {

struct MonteCarloOptions {
  int runs = 1000;
  std::uint64_t seed = 1;
  int threads = 0;                    // 0: all cores
  bool weighted = true;               // weight each drawn reading by its covariance, as fvm verify does
  // Machine: the readings (and the validation readings) carry their own covariances (multilaterated points,
  // artefacts::CarriesCovariances) in Observation::covariance: each run draws their noise from those, not from the
  // tracker's model.
  bool readings_carry_covariances = false;
  bool validation_carries_covariances = false;
  // Machine: the truth carries what the reference leaves in the readings (stage/residual_field.h). Off where the
  // reference's pose is not the one the readings were taken from (tracker placement moves the truth's tracker).
  bool truth_keeps_residuals = true;
  std::function<void()> on_run_done;  // after each run, from any thread (progress); may be empty
};

// Calls run(i) for i in [0, runs) on `threads` threads (0: all cores), each index exactly once.
void ForEachRun(int runs, int threads, const std::function<void(int)>& run);

// What every run reports: whether it converged and how its predictions differ from the reference's.
struct MonteCarloRun {
  bool converged = false;
  // The run's prediction minus the reference's at every evaluation point, mm (machine: the readings' commands, then
  // the validation's, in the tracker frame, gauge-free as both are fitted to readings in that frame; stage: the
  // validation centres, or the identification's without validation, each referenced to its first tile).
  std::vector<Eigen::Vector3d> deviation_mm;
};

struct MachineMonteCarloRun : MonteCarloRun {
  ResidualSummary initial;     // the ideal machine (the reference's initial pose) against the run's drawn readings
  ResidualSummary final;       // the run's model against its own drawn readings
  ResidualSummary validation;  // the run's model against validation readings drawn afresh (points 0 without them)
  Pose pose;                   // the run's tracker pose
  std::vector<double> initial_um, final_um;  // per reading: |ideal machine - drawn reading|, |run's model - drawn reading|
};

// `layout` is what each run identifies (MachineLayout, before any rank treatment); `reference` is the verification
// of the real readings (its identified calibration and pose, with what it leaves in them, are the simulated truth;
// its initial pose states the ideal machine's error); `readings` gives the commands, tools and residuals to draw at;
// `validation` (may be empty) the readings the runs are judged on, drawn afresh around the truth they show (their
// covariance is read only with options.validation_carries_covariances); `identification` the options of the
// original fit (instrument held or estimated, tool offsets; pose and threads are set here). Throws
// std::invalid_argument for runs < 1 or an identification without a tracker pose.
std::vector<MachineMonteCarloRun> MachineMonteCarlo(const ParameterLayout& layout, const VerificationResult& reference,
                                                    const std::vector<Observation>& readings,
                                                    const std::vector<Observation>& validation, const TrackerNoise& noise,
                                                    const IdentificationOptions& identification,
                                                    const MonteCarloOptions& options);

struct StageMonteCarloRun : MonteCarloRun {
  double fit_mean_mm = 0, fit_rms_mm = 0;  // the run's residuals on its own drawn centres
  ResidualSummary validation;              // the run's calibration on the validation centres (count 0 without)
};

// `layout` is what each run identifies (the model, before rank treatment); `reference` the identification of the
// real centres; `identify` the identification placements (commands, groups, anchors); `validate` (may be null) the
// validation placements, judged as fvm calibrate does (stage::Validate); `centre_sigma_mm` the standard deviation
// of each coordinate of a stitched centre. Throws std::invalid_argument for runs < 1 or a negative sigma.
std::vector<StageMonteCarloRun> StageMonteCarlo(const ParameterLayout& layout, const IdentificationResult& reference,
                                                const MeasurementSet& identify, const MeasurementSet* validate,
                                                double centre_sigma_mm, const IdentificationOptions& identification,
                                                const MonteCarloOptions& options);

// Mean, standard deviation (n - 1) and the 2.5 / 95 / 97.5 % quantiles (linear interpolation) of a sample.
struct SampleSummary {
  int n = 0;
  double mean = 0, sd = 0, p2_5 = 0, p95 = 0, p97_5 = 0, max = 0;
};
SampleSummary SummarizeSample(std::vector<double> values);

// The spread of one evaluation point's deviations over the runs.
struct PointSpread {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // about the mean deviation, mm^2
  Eigen::Vector3d mean_mm = Eigen::Vector3d::Zero();     // mean deviation (bias of the re-identification), mm
  Eigen::Vector3d semi_axes_mm = Eigen::Vector3d::Zero();  // of the 95 % ellipsoid (chi^2 with 3 d.o.f.), ascending
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();     // their directions (columns)
  double u95_mm = 0;  // 95 % quantile of |deviation|: the radius that holds 95 % of the runs' predictions
};
template <typename Run>
std::vector<PointSpread> PointSpreads(const std::vector<Run>& runs);

// Distance errors over point pairs: for each run and pair (i, j) of the first `max_points` evaluation points, the
// change of the predicted distance, (d_i - d_j) . (p_i - p_j) / |p_i - p_j| to first order; per pair the 95 %
// quantile of its magnitude over the runs, summarised over the pairs, and the pair where it is largest.
struct PairSpread {
  int pairs = 0;
  SampleSummary all_um;   // of the pairs' 95 % quantiles, um
  int worst_i = -1, worst_j = -1;
  double worst_u95_um = 0;  // 95 % quantile of |distance error| of the worst pair
};
PairSpread PairDistanceSpread(const std::vector<MachineMonteCarloRun>& runs, const std::vector<Eigen::Vector3d>& points_mm,
                              int max_points = 200);

// The [ISO/TS 15530-3] budget as [Pérez 2017] applies it: U = k sqrt(u_cal^2 + u_p^2 + u_b^2 + u_w^2).
//   u_cal: the reference's calibration, given;
//   u_p:   2 x the standard deviation of the simulated positions (as [Pérez 2017] defines it): 2 x the rms over the
//          evaluation points of their 3D standard deviation sqrt(trace Cov) from the Monte Carlo;
//   u_b:   repeatability, s / sqrt(n): from readings repeated at one command (same tool), pooled 3D standard
//          deviation s over the repeated commands and n their mean count; without repeats, s from the noise model
//          (the tracker's: rms over the readings of sqrt(trace Cov); the microscope's: sqrt(3) sigma) and n = 1;
//   u_w:   the workpiece's expansion: CTE x length x temperature half-range / sqrt(3) (rectangular), the length the
//          diagonal of the commanded points' span.
struct BudgetInputs {
  double u_cal_mm = 0.0;
  double temperature_half_range_k = 0.2;  // [Pérez 2017]: +-0.2 C
  double cte_per_k = 11.5e-6;             // steel; [Pérez 2017] used 24e-6 for an aluminium plate
  double k = 2.0;
};
struct UncertaintyBudget {
  double u_cal_mm = 0, u_p_mm = 0, u_b_mm = 0, u_w_mm = 0, U_mm = 0, k = 2;
  double length_mm = 0;
  int repeated_commands = 0;  // commands read more than once (0: u_b from the noise model)
};
// `reading_sd_mm`: the 3D standard deviation of one reading under the noise model, used without repeats.
UncertaintyBudget Budget(const std::vector<PointSpread>& spreads, const std::vector<Observation>& readings,
                         double reading_sd_mm, const BudgetInputs& inputs);
// The rms over the readings of sqrt(trace Cov) under the tracker's noise model.
double TrackerReadingSd(const std::vector<Observation>& readings, const TrackerNoise& noise);

// Covariance propagation, the fast stand-in for a Monte Carlo (tracker placement): the linearised covariance (mm^2)
// of each point's predicted reading when `calibration`'s free coefficients and, with `estimate_pose`, the tracker
// pose are identified from weighted readings at `points` by a tracker at `pose` with `noise`:
// C_i = J_i (J^T W J)^+ J_i^T, J the Jacobian (central differences) of the predicted readings, W = their inverse
// covariances. The rank treatment is the calibration's (its fixed coefficients stay fixed).
std::vector<Eigen::Matrix3d> PredictedPointCovariances(const Calibration& calibration, const Pose& pose, bool estimate_pose,
                                                       const std::vector<Observation>& points,
                                                       const std::vector<Eigen::Vector3d>& tool_offsets,
                                                       const TrackerNoise& noise);
// The 95 % quantile of |d| for d ~ N(0, covariance): the covariance counterpart of PointSpread::u95_mm, from a fixed
// set of 4000 seeded normal draws (the same for every call, so rankings are not noisy).
double U95OfCovariance(const Eigen::Matrix3d& covariance);

// ---- implementation of the template ----
std::vector<PointSpread> PointSpreads(const std::vector<const MonteCarloRun*>& runs);
template <typename Run>
std::vector<PointSpread> PointSpreads(const std::vector<Run>& runs) {
  std::vector<const MonteCarloRun*> base;
  for (const Run& r : runs) base.push_back(&r);
  return PointSpreads(base);
}

}  // namespace fvm::stage
