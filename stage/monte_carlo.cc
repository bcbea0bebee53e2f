#include "stage/monte_carlo.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstddef>
#include <map>
#include <tuple>
#include <cmath>
#include <stdexcept>

#include "core/dense_decomposition.h"
#include "core/random.h"
#include "stage/residual_field.h"

namespace fvm::stage {

void ForEachRun(int runs, int threads, const std::function<void(int)>& run) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, runs, 1), [&](const tbb::blocked_range<int>& range) {
      for (int i = range.begin(); i != range.end(); ++i) run(i);
    });
  });
}

namespace {

// Each reading's noise covariance: its own (multilaterated points) or the tracker's model at it.
std::vector<Eigen::Matrix3d> NoiseCovariances(const std::vector<Observation>& set, bool own, const TrackerNoise& noise) {
  std::vector<Eigen::Matrix3d> out;
  for (const Observation& o : set) out.push_back(own ? o.covariance : noise.Covariance(o.measured));
  return out;
}

// A reading of `truth` with fresh noise: normal with its own covariance (lower Cholesky factor `own`, when not null),
// else the tracker's, normal in range, azimuth and elevation. Three draws either way.
Eigen::Vector3d DrawReading(const Eigen::Vector3d& truth, const Eigen::Matrix3d* own, const TrackerNoise& noise, Random& random) {
  const double a = random.Normal(), b = random.Normal(), c = random.Normal();
  return own != nullptr ? Eigen::Vector3d(truth + *own * Eigen::Vector3d(a, b, c)) : noise.Perturb(truth, a, b, c);
}

std::vector<Eigen::Matrix3d> CholeskyFactors(const std::vector<Eigen::Matrix3d>& covariances) {
  std::vector<Eigen::Matrix3d> out;
  for (const Eigen::Matrix3d& c : covariances) {
    out.push_back(Decompose<Eigen::LLT<Eigen::Matrix3d>>(c, "Monte Carlo: a reading's covariance").matrixL());
  }
  return out;
}

}  // namespace

std::vector<MachineMonteCarloRun> MachineMonteCarlo(const ParameterLayout& layout, const VerificationResult& verification,
                                                    const std::vector<Observation>& readings,
                                                    const std::vector<Observation>& validation, const TrackerNoise& noise,
                                                    const IdentificationOptions& identification,
                                                    const MonteCarloOptions& options) {
  if (options.runs < 1) throw std::invalid_argument("a Monte Carlo needs at least one run");
  if (identification.instrument == InstrumentPose::kNone) {
    throw std::invalid_argument("a machine Monte Carlo needs the tracker pose: held or estimated");
  }
  const IdentificationResult& reference = verification.identified;
  const Calibration& truth = reference.calibration;
  const std::vector<Eigen::Vector3d>& tools = identification.tool_offsets;
  std::vector<Observation> evaluation = readings;
  evaluation.insert(evaluation.end(), validation.begin(), validation.end());
  const std::vector<Eigen::Vector3d> model_readings = PredictedReadings(truth.layout, &truth.values, reference.pose, readings, tools);
  const std::vector<Eigen::Vector3d> true_evaluation =
      PredictedReadings(truth.layout, &truth.values, reference.pose, evaluation, tools);

  // The truth: the identified model plus what it leaves in the readings, less the noise's expected share of that
  // (stage/residual_field.h); the fit's degrees of freedom are what its noise alone leaves.
  const std::vector<Eigen::Matrix3d> reading_covariances = NoiseCovariances(readings, options.readings_carry_covariances, noise);
  std::vector<Eigen::Vector3d> left(readings.size());
  for (size_t i = 0; i < readings.size(); ++i) {
    left[i] = options.truth_keeps_residuals ? Eigen::Vector3d(readings[i].measured - model_readings[i]) : Eigen::Vector3d::Zero();
  }
  // What the fit leaves of the noise: the share dof / equations of each reading's covariance, on average.
  const int pose_count = identification.instrument == InstrumentPose::kEstimated ? 6 : 0;
  const double equations = 3.0 * static_cast<double>(readings.size());
  const double left_share = std::max(0.0, equations - truth.layout.NumFree() - pose_count) / std::max(1.0, equations);
  std::vector<Eigen::Matrix3d> left_covariances = reading_covariances;
  for (Eigen::Matrix3d& c : left_covariances) c *= left_share;
  const ResidualField reading_field = ShrunkResidualField(left, left_covariances);
  std::vector<Eigen::Vector3d> true_readings = model_readings;
  for (size_t i = 0; i < readings.size(); ++i) true_readings[i] += reading_field.offsets_mm[i];
  const std::vector<Eigen::Matrix3d> reading_factors =
      options.readings_carry_covariances ? CholeskyFactors(reading_covariances) : std::vector<Eigen::Matrix3d>{};
  const std::vector<Eigen::Matrix3d> validation_covariances =
      NoiseCovariances(validation, options.validation_carries_covariances, noise);
  const std::vector<Eigen::Matrix3d> validation_factors =
      options.validation_carries_covariances ? CholeskyFactors(validation_covariances) : std::vector<Eigen::Matrix3d>{};

  IdentificationOptions run_options = identification;
  run_options.pose = reference.pose;  // held, or where the estimate starts: the truth of the simulation
  run_options.num_threads = 1;        // the runs are the parallel work; one thread each keeps them deterministic

  std::vector<MachineMonteCarloRun> runs(static_cast<size_t>(options.runs));
  std::vector<std::vector<Eigen::Vector3d>> validation_noise(runs.size());
  const size_t n_readings = readings.size();
  const auto one_run = [&](int index) {
    Random random(StreamSeed(options.seed, static_cast<std::uint64_t>(index)));
    std::vector<Observation> drawn = readings;
    for (size_t i = 0; i < drawn.size(); ++i) {
      drawn[i].measured = DrawReading(true_readings[i], reading_factors.empty() ? nullptr : &reading_factors[i], noise, random);
      if (!options.weighted) {
        drawn[i].covariance = Eigen::Matrix3d::Zero();
      } else if (!options.readings_carry_covariances) {
        drawn[i].covariance = noise.Covariance(drawn[i].measured);
      }  // else: the reading's own, as given
    }
    // The validation readings' fresh noise, drawn now so that the run's stream alone decides it.
    std::vector<Eigen::Vector3d>& validation_drawn = validation_noise[static_cast<size_t>(index)];
    for (size_t p = 0; p < validation.size(); ++p) {
      const Eigen::Vector3d& at = true_evaluation[n_readings + p];
      validation_drawn.push_back(DrawReading(at, validation_factors.empty() ? nullptr : &validation_factors[p], noise, random) - at);
    }
    const IdentificationResult r = Identify(layout, drawn, run_options);
    MachineMonteCarloRun& out = runs[static_cast<size_t>(index)];
    out.converged = r.converged;
    out.pose = r.pose;
    out.final = Summarize(r.residuals);
    const std::vector<Eigen::Vector3d> ideal = VolumetricResiduals(layout, nullptr, verification.initial_pose, drawn, tools);
    out.initial = Summarize(ideal);
    for (size_t i = 0; i < drawn.size(); ++i) {
      out.initial_um.push_back(ideal[i].norm() * 1e3);
      out.final_um.push_back(r.residuals[i].norm() * 1e3);
    }
    const Calibration& c = r.calibration;
    out.deviation_mm = PredictedReadings(c.layout, &c.values, r.pose, evaluation, tools);
    for (size_t i = 0; i < evaluation.size(); ++i) out.deviation_mm[i] -= true_evaluation[i];
    if (options.on_run_done) options.on_run_done();
  };
  ForEachRun(options.runs, options.threads, one_run);
  if (validation.empty()) return runs;

  // The validation readings' truth: the model plus what it leaves there, less the expected share of their noise and
  // of the model's own estimation error (stage/residual_field.h: HeldOutResidualField), whose covariance over the
  // points the runs' deviations there give.
  const std::vector<PointSpread> spreads = PointSpreads(runs);
  std::vector<Eigen::Vector3d> held_out_left(validation.size());
  for (size_t p = 0; p < validation.size(); ++p) {
    held_out_left[p] = options.truth_keeps_residuals ? Eigen::Vector3d(validation[p].measured - true_evaluation[n_readings + p])
                                                     : Eigen::Vector3d::Zero();
  }
  // Validation readings whose residuals are far smaller than their noise would make them (beyond three standard
  // deviations of sum |r|^2: 2 sum tr C^2) do not carry it: noise-free simulated ones. Their residuals are then all
  // field and model error, and the runs draw no noise for them.
  double power = 0, expected = 0, variance = 0;
  for (size_t p = 0; p < validation.size(); ++p) {
    power += held_out_left[p].squaredNorm();
    expected += validation_covariances[p].trace() + spreads[n_readings + p].covariance.trace();
    variance += 2.0 * (validation_covariances[p] * validation_covariances[p]).trace();
  }
  const bool noise_free = options.truth_keeps_residuals && power < expected - 3.0 * std::sqrt(variance);
  const std::vector<Eigen::Matrix3d> held_out_noise =
      noise_free ? std::vector<Eigen::Matrix3d>(validation.size(), Eigen::Matrix3d::Zero()) : validation_covariances;
  std::vector<std::vector<Eigen::Vector3d>> estimation_errors;
  for (const MachineMonteCarloRun& r : runs) {
    estimation_errors.emplace_back(r.deviation_mm.begin() + static_cast<std::ptrdiff_t>(n_readings), r.deviation_mm.end());
  }
  // The estimation error lives in the span of the coefficients the reference identified and its pose.
  const ResidualField validation_field =
      HeldOutResidualField(held_out_left, held_out_noise, estimation_errors, truth.layout.NumFree() + pose_count);
  const double noise_scale = noise_free ? 0.0 : 1.0;
  for (size_t k = 0; k < runs.size(); ++k) {
    // Run's model - its drawn validation reading = (model - reference model) - field - noise.
    std::vector<Eigen::Vector3d> judged(validation.size());
    for (size_t p = 0; p < validation.size(); ++p) {
      judged[p] = runs[k].deviation_mm[n_readings + p] - validation_field.offsets_mm[p] - noise_scale * validation_noise[k][p];
    }
    runs[k].validation = Summarize(judged);
  }
  return runs;
}

namespace {

// What the model predicts for each observation's measurement (stitched centre), with its group's anchor.
std::vector<Eigen::Vector3d> PredictedCentres(const Calibration& c, const MeasurementSet& set, bool anchored) {
  std::vector<Eigen::Vector3d> out;
  for (const Observation& o : set.observations) {
    const Eigen::Vector3d* anchor = anchored ? &set.anchors.at(static_cast<size_t>(o.group)) : nullptr;
    out.push_back(Predict(c.layout, c.values.data(), Eigen::Vector3d(o.command), anchor));
  }
  return out;
}

}  // namespace

std::vector<StageMonteCarloRun> StageMonteCarlo(const ParameterLayout& layout, const IdentificationResult& reference,
                                                const MeasurementSet& identify, const MeasurementSet* validate,
                                                double centre_sigma_mm, const IdentificationOptions& identification,
                                                const MonteCarloOptions& options) {
  if (options.runs < 1) throw std::invalid_argument("a Monte Carlo needs at least one run");
  if (!(centre_sigma_mm >= 0.0)) throw std::invalid_argument("the centres' noise must be zero or positive");
  const Calibration& truth = reference.calibration;
  const bool anchored = identification.anchor == Anchor::kFirstTile;
  const std::vector<Eigen::Vector3d> true_centres = PredictedCentres(truth, identify, anchored);
  // Evaluated where fvm calibrate validates: each validation placement referenced to its own first tile.
  const MeasurementSet& evaluation = validate != nullptr ? *validate : identify;
  const std::vector<Eigen::Vector3d> true_evaluation = PredictedCentres(truth, evaluation, !evaluation.anchors.empty());
  IdentificationOptions run_options = identification;
  run_options.num_threads = 1;
  std::vector<StageMonteCarloRun> runs(static_cast<size_t>(options.runs));
  ForEachRun(options.runs, options.threads, [&](int index) {
    Random random(StreamSeed(options.seed, static_cast<std::uint64_t>(index)));
    std::vector<Observation> drawn = identify.observations;
    for (size_t i = 0; i < drawn.size(); ++i) {
      const double nx = random.Normal(), ny = random.Normal(), nz = random.Normal();
      drawn[i].measured = true_centres[i] + centre_sigma_mm * Eigen::Vector3d(nx, ny, nz);
    }
    const IdentificationResult r = Identify(layout, drawn, run_options);
    StageMonteCarloRun& out = runs[static_cast<size_t>(index)];
    out.converged = r.converged;
    out.fit_mean_mm = r.residual_summary.mean_mm;
    out.fit_rms_mm = r.residual_summary.rms_mm;
    if (validate != nullptr) out.validation = Validate(&r.calibration, validate->observations, validate->anchors, identification.frame);
    out.deviation_mm = PredictedCentres(r.calibration, evaluation, !evaluation.anchors.empty());
    for (size_t i = 0; i < out.deviation_mm.size(); ++i) out.deviation_mm[i] -= true_evaluation[i];
    if (options.on_run_done) options.on_run_done();
  });
  return runs;
}

namespace {

double Quantile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const double at = p * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(at));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (at - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

constexpr double kChi2Of3At95 = 7.814727903251178;  // chi^2 quantile, 3 d.o.f., 0.95

}  // namespace

SampleSummary SummarizeSample(std::vector<double> values) {
  SampleSummary s;
  s.n = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  for (double v : values) s.mean += v;
  s.mean /= s.n;
  for (double v : values) s.sd += (v - s.mean) * (v - s.mean);
  s.sd = s.n > 1 ? std::sqrt(s.sd / (s.n - 1)) : 0.0;
  s.p2_5 = Quantile(values, 0.025);
  s.p95 = Quantile(values, 0.95);
  s.p97_5 = Quantile(values, 0.975);
  s.max = values.back();
  return s;
}

std::vector<PointSpread> PointSpreads(const std::vector<const MonteCarloRun*>& runs) {
  if (runs.empty()) return {};
  const size_t points = runs.front()->deviation_mm.size();
  std::vector<PointSpread> out(points);
  std::vector<double> norms(runs.size());
  for (size_t p = 0; p < points; ++p) {
    PointSpread& s = out[p];
    for (const MonteCarloRun* r : runs) s.mean_mm += r->deviation_mm[p];
    s.mean_mm /= static_cast<double>(runs.size());
    for (size_t k = 0; k < runs.size(); ++k) {
      const Eigen::Vector3d d = runs[k]->deviation_mm[p];
      s.covariance += (d - s.mean_mm) * (d - s.mean_mm).transpose();
      norms[k] = d.norm();
    }
    if (runs.size() > 1) s.covariance /= static_cast<double>(runs.size() - 1);
    const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(s.covariance, "Monte Carlo: the scatter of a point");
    s.semi_axes_mm = (eig.eigenvalues().cwiseMax(0.0) * kChi2Of3At95).cwiseSqrt();
    s.axes = eig.eigenvectors();
    std::vector<double> sorted = norms;
    std::sort(sorted.begin(), sorted.end());
    s.u95_mm = Quantile(sorted, 0.95);
  }
  return out;
}

PairSpread PairDistanceSpread(const std::vector<MachineMonteCarloRun>& runs, const std::vector<Eigen::Vector3d>& points_mm,
                              int max_points) {
  PairSpread out;
  const size_t n = std::min(points_mm.size(), static_cast<size_t>(std::max(max_points, 0)));
  if (runs.empty() || n < 2) return out;
  std::vector<double> per_pair_u95, errors(runs.size());
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const Eigen::Vector3d delta = points_mm[i] - points_mm[j];
      if (!(delta.norm() > 0.0)) continue;
      const Eigen::Vector3d unit = delta.normalized();
      for (size_t k = 0; k < runs.size(); ++k) {
        errors[k] = std::abs((runs[k].deviation_mm[i] - runs[k].deviation_mm[j]).dot(unit)) * 1e3;
      }
      std::sort(errors.begin(), errors.end());
      const double u95 = Quantile(errors, 0.95);
      per_pair_u95.push_back(u95);
      if (u95 > out.worst_u95_um) {
        out.worst_u95_um = u95;
        out.worst_i = static_cast<int>(i);
        out.worst_j = static_cast<int>(j);
      }
    }
  }
  out.pairs = static_cast<int>(per_pair_u95.size());
  out.all_um = SummarizeSample(std::move(per_pair_u95));
  return out;
}

double TrackerReadingSd(const std::vector<Observation>& readings, const TrackerNoise& noise) {
  if (readings.empty()) return 0.0;
  double trace = 0;
  for (const Observation& o : readings) trace += noise.Covariance(o.measured).trace();
  return std::sqrt(trace / static_cast<double>(readings.size()));
}

UncertaintyBudget Budget(const std::vector<PointSpread>& spreads, const std::vector<Observation>& readings,
                         double reading_sd_mm, const BudgetInputs& inputs) {
  UncertaintyBudget b;
  b.k = inputs.k;
  b.u_cal_mm = inputs.u_cal_mm;
  double trace_sum = 0;
  for (const PointSpread& s : spreads) trace_sum += s.covariance.trace();
  if (!spreads.empty()) b.u_p_mm = 2.0 * std::sqrt(trace_sum / static_cast<double>(spreads.size()));

  // Repeats: readings of one command with one tool.
  std::map<std::tuple<double, double, double, int>, std::vector<Eigen::Vector3d>> groups;
  for (const Observation& o : readings) groups[{o.command.x(), o.command.y(), o.command.z(), o.tool}].push_back(o.measured);
  double squares = 0, dof = 0, count = 0;
  for (const auto& [key, measured] : groups) {
    if (measured.size() < 2) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& m : measured) mean += m;
    mean /= static_cast<double>(measured.size());
    for (const Eigen::Vector3d& m : measured) squares += (m - mean).squaredNorm();
    dof += static_cast<double>(measured.size() - 1);
    count += static_cast<double>(measured.size());
    ++b.repeated_commands;
  }
  if (b.repeated_commands > 0) {
    b.u_b_mm = std::sqrt(squares / dof) / std::sqrt(count / b.repeated_commands);
  } else {
    b.u_b_mm = reading_sd_mm;
  }

  if (!readings.empty()) {
    Eigen::Vector3d lo = readings.front().command, hi = lo;
    for (const Observation& o : readings) lo = lo.cwiseMin(o.command), hi = hi.cwiseMax(o.command);
    b.length_mm = (hi - lo).norm();
  }
  b.u_w_mm = inputs.cte_per_k * b.length_mm * inputs.temperature_half_range_k / std::sqrt(3.0);
  b.U_mm = b.k * std::sqrt(b.u_cal_mm * b.u_cal_mm + b.u_p_mm * b.u_p_mm + b.u_b_mm * b.u_b_mm + b.u_w_mm * b.u_w_mm);
  return b;
}

std::vector<Eigen::Matrix3d> PredictedPointCovariances(const Calibration& calibration, const Pose& pose, bool estimate_pose,
                                                       const std::vector<Observation>& points,
                                                       const std::vector<Eigen::Vector3d>& tool_offsets,
                                                       const TrackerNoise& noise) {
  const ParameterLayout& layout = calibration.layout;
  const int n_free = layout.NumFree();
  const int n = n_free + (estimate_pose ? 6 : 0);
  const Eigen::Index m = static_cast<Eigen::Index>(points.size());
  const Eigen::VectorXd plausible = PlausibleSizes(layout);
  const auto predict = [&](const std::vector<double>& values, const Pose& at) {
    return PredictedReadings(layout, &values, at, points, tool_offsets);
  };
  Eigen::MatrixXd jacobian(3 * m, n);
  for (int j = 0; j < n; ++j) {
    std::vector<double> plus = calibration.values, minus = calibration.values;
    Pose pose_plus = pose, pose_minus = pose;
    double h = 0;
    if (j < n_free) {
      h = 1e-4 * plausible[j];
      plus[static_cast<size_t>(j)] += h;
      minus[static_cast<size_t>(j)] -= h;
    } else {
      const int k = j - n_free;
      h = k < 3 ? 1e-3 : 1e-6;  // mm, rad
      (k < 3 ? pose_plus.translation : pose_plus.rotation)[k % 3] += h;
      (k < 3 ? pose_minus.translation : pose_minus.rotation)[k % 3] -= h;
    }
    const std::vector<Eigen::Vector3d> a = predict(plus, pose_plus), b = predict(minus, pose_minus);
    for (Eigen::Index i = 0; i < m; ++i) jacobian.block<3, 1>(3 * i, j) = (a[static_cast<size_t>(i)] - b[static_cast<size_t>(i)]) / (2 * h);
  }
  const std::vector<Eigen::Vector3d> readings = predict(calibration.values, pose);
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::MatrixXd ji = jacobian.middleRows(3 * i, 3);
    normal += ji.transpose() * noise.Covariance(readings[static_cast<size_t>(i)]).inverse() * ji;
  }
  const Eigen::MatrixXd parameter_covariance =
      Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(normal, "Monte Carlo: the calibration's normal equations")
          .pseudoInverse();
  std::vector<Eigen::Matrix3d> out;
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::MatrixXd ji = jacobian.middleRows(3 * i, 3);
    out.push_back(ji * parameter_covariance * ji.transpose());
  }
  return out;
}

double U95OfCovariance(const Eigen::Matrix3d& covariance) {
  static const std::vector<Eigen::Vector3d> draws = [] {
    Random random(StreamSeed(95, 3));
    std::vector<Eigen::Vector3d> z(4000);
    for (Eigen::Vector3d& v : z) v = Eigen::Vector3d(random.Normal(), random.Normal(), random.Normal());
    return z;
  }();
  const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(covariance, "U95 of a point's covariance");
  const Eigen::Vector3d scale = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  std::vector<double> norms;
  norms.reserve(draws.size());
  for (const Eigen::Vector3d& z : draws) norms.push_back(scale.cwiseProduct(z).norm());  // |Q diag(s) z| = |diag(s) z|
  std::sort(norms.begin(), norms.end());
  return Quantile(norms, 0.95);
}

}  // namespace fvm::stage
