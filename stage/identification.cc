#include "stage/identification.h"

#include <ceres/ceres.h>
#include <fmt/core.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <map>
#include <memory>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <thread>

#include "core/dense_decomposition.h"
#include "stage/identification_rank.h"
#include "stage/observation_model.h"
#include "stage/residual_summary.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {
namespace {

// Observations as one Ceres residual block over the coefficients in units of their plausible size (coefficient =
// scale * parameter, so every parameter is of order one) and, when estimated, the pose correction in the same
// kind of units. A block holds one placement, whose first tile is then evaluated once, or a single observation
// when a robust loss must see each centre's error on its own.
class BlockCost final : public ceres::CostFunction {
 public:
  BlockCost(const ParameterLayout& layout, const Eigen::VectorXd& scale, std::vector<const PreparedObservation*> block,
            const Prepared& prepared)
      : layout_(layout), scale_(scale), block_(std::move(block)), prepared_(prepared) {
    set_num_residuals(3 * static_cast<int>(block_.size()));
    if (scale.size() > 0) mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(scale.size()));
    if (prepared.estimate_pose) mutable_parameter_block_sizes()->push_back(kPoseParameters);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Index n = scale_.size();
    std::array<double, kMaxCoefficients> free{}, all{};
    for (Eigen::Index i = 0; i < n; ++i) free[static_cast<size_t>(i)] = scale_[i] * parameters[0][i];
    layout_.Expand(free.data(), all.data());
    const int pose_block = n > 0 ? 1 : 0;
    InstrumentMap instrument;
    if (prepared_.estimate_pose) {
      double pose6[kPoseParameters];
      for (int i = 0; i < kPoseParameters; ++i) {
        pose6[i] = prepared_.pose6[static_cast<size_t>(i)] + prepared_.pose_scale[i] * parameters[pose_block][i];
      }
      instrument = InstrumentMap(pose6);
    } else if (prepared_.has_pose) {
      instrument = InstrumentMap(prepared_.pose6.data());
    }
    const bool want_coefficients = jacobians != nullptr && n > 0 && jacobians[0] != nullptr;
    const bool want_pose = jacobians != nullptr && prepared_.estimate_pose && jacobians[pose_block] != nullptr;
    // The stitched frame is common to the block (every observation of a block shares its anchor).
    std::optional<AnchorFrame> anchor;
    if (block_.front()->anchor >= 0) {
      anchor = EvaluateAnchor(layout_, *block_.front()->chain, free.data(), all.data(), prepared_,
                              prepared_.anchors[static_cast<size_t>(block_.front()->anchor)], want_coefficients);
    }
    Eigen::Matrix3Xd jacobian;
    Eigen::Matrix<double, 3, kPoseParameters> pose_jacobian;
    for (size_t k = 0; k < block_.size(); ++k) {
      const Eigen::Vector3d r =
          ObservationResidual(layout_, free.data(), all.data(), prepared_, instrument, *block_[k], anchor ? &*anchor : nullptr,
                              want_coefficients ? &jacobian : nullptr, want_pose ? &pose_jacobian : nullptr);
      for (int c = 0; c < 3; ++c) residuals[3 * k + static_cast<size_t>(c)] = r[c];
      if (want_coefficients) {
        Eigen::Map<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>> out(jacobians[0] + 3 * k * static_cast<size_t>(n), 3, n);
        out = jacobian * scale_.asDiagonal();
      }
      if (want_pose) {
        Eigen::Map<Eigen::Matrix<double, 3, kPoseParameters, Eigen::RowMajor>> out(jacobians[pose_block] + 3 * k * kPoseParameters);
        out = pose_jacobian * prepared_.pose_scale.asDiagonal();
      }
    }
    return true;
  }

 private:
  const ParameterLayout& layout_;
  const Eigen::VectorXd& scale_;
  std::vector<const PreparedObservation*> block_;
  const Prepared& prepared_;
};

// Calls `report` after every solver iteration (the state is current: update_state_every_iteration).
class IterationLog : public ceres::IterationCallback {
 public:
  explicit IterationLog(std::function<void()> report) : report_(std::move(report)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    report_();
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<void()> report_;
};

}  // namespace

void IdentificationOptions::Check() const {
  if (loss != "none" && loss != "huber" && loss != "cauchy") {
    throw std::invalid_argument("unknown loss '" + loss + "': use none, huber or cauchy");
  }
  if (num_threads < 0) throw std::invalid_argument("num_threads must be 0 (all cores) or positive");
  if (!(max_error_mm >= 0)) throw std::invalid_argument("the error bound must be positive (0: the default from the travel)");
  if (!(loss_scale_mm > 0) || !(alias_tolerance > 0) || !(max_relative_uncertainty > 0) || !(noise_floor_mm > 0)) {
    throw std::invalid_argument("identification tolerances must be positive");
  }
}

Eigen::Vector3d FirstTile(std::span<const Eigen::Vector3d> positions, const Eigen::Vector3d& offset) {
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::Vector2d corner(inf, -inf);
  for (const Eigen::Vector3d& p : positions) {
    if (p.allFinite()) corner = Eigen::Vector2d(std::min(corner.x(), p.x()), std::max(corner.y(), p.y()));
  }
  if (!corner.allFinite()) throw std::invalid_argument("a measurement without points has no first tile");
  // Its height is that of the part under it: the point nearest the corner (a tilted part is not at its mean z there).
  const Eigen::Vector3d* nearest = nullptr;
  for (const Eigen::Vector3d& p : positions) {
    if (!p.allFinite()) continue;
    if (!nearest || (p.head<2>() - corner).squaredNorm() < (nearest->head<2>() - corner).squaredNorm()) nearest = &p;
  }
  return Eigen::Vector3d(corner.x(), corner.y(), nearest->z()) + offset;
}

Eigen::VectorXd PlausibleSizes(const ParameterLayout& layout) {
  Eigen::VectorXd tau(layout.NumFree());
  for (int slot = 0; slot < layout.NumFree(); ++slot) {
    const ParameterLayout::Coefficient& c = FreeCoefficient(layout, slot);
    const TermSpec& spec = layout.term(c.term);
    const Travel& travel = layout.travel()[static_cast<size_t>(layout.chain().ArgumentAxis(c.term))];
    double reach = 0.0;  // largest |basis function| over the travel
    for (int k = 0; k <= 100; ++k) {
      const double q = travel.min + (travel.max - travel.min) * k / 100.0;
      double basis[kMaxOrder + 1];
      EvaluateBasis(spec.basis, spec.order, NormalisedCoordinate(spec.basis, travel, q), basis);
      reach = std::max(reach, std::abs(basis[c.power]));
    }
    const ErrorTerm& term = GetErrorTerm(c.term);
    double size = term.kind == ErrorKind::kTranslation ? 0.5 : 1e-3;
    // A squareness term multiplies its carrier's coordinate: 1 mrad is its size as an angle.
    tau[slot] = size / std::max(reach, 1e-12);
  }
  return tau;
}

Eigen::Vector3d Predict(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& command,
                        const Eigen::Vector3d* anchor) {
  Eigen::Vector3d seen = Forward(layout, free, command);
  if (anchor) seen -= Forward(layout, free, Eigen::Vector3d(*anchor)) - *anchor;
  return seen;
}

Eigen::Vector3d ModelResidual(const ParameterLayout& layout, const double* free, const Observation& observation,
                              const Eigen::Vector3d* anchor) {
  return Predict(layout, free, Eigen::Vector3d(observation.command), anchor) - observation.measured;
}

const std::vector<std::string>& PoseParameterNames() {
  static const std::vector<std::string> names{"pose_tx", "pose_ty", "pose_tz", "pose_rx", "pose_ry", "pose_rz"};
  return names;
}

namespace {

// The variance factor: residuals per coordinate in mm (equal weights), or chi^2 per degree of freedom (weighted;
// never below 1, since the readings cannot be better than their covariances say).
double VarianceFactor(bool weighted, double noise_floor_mm, double rss, double dof) {
  const double s = std::sqrt(rss / dof);
  return weighted ? std::max(s, 1.0) : std::max(s, noise_floor_mm);
}

// The observed coordinates (three a point, fewer where a covariance leaves one unobserved). Throws
// std::invalid_argument when they cannot determine the model or refer to what was not given.
int CountEquations(const ParameterLayout& layout, const std::vector<Observation>& observations,
                   const IdentificationOptions& options, int pose_count) {
  const int m = static_cast<int>(observations.size());
  const bool estimate_pose = pose_count > 0;
  int equations = 0;
  for (const Observation& o : observations) {
    for (int c = 0; c < 3; ++c) equations += std::isinf(o.covariance(c, c)) ? 0 : 1;
  }
  if (equations < layout.NumFree() + pose_count) {
    throw std::invalid_argument(fmt::format(
        "{} points give {} equations, fewer than the {} coefficients of the model{}: measure more points or choose a "
        "smaller model", m, equations, layout.NumFree(), estimate_pose ? " and the 6 of the instrument pose" : ""));
  }
  if (options.instrument != InstrumentPose::kNone && layout.chain().instrument) {
    throw std::invalid_argument("the chain already carries an instrument pose: give it as the identification's pose instead");
  }
  const size_t tools = std::max<size_t>(1, options.tool_offsets.size());
  for (const Observation& o : observations) {
    if (o.tool < 0 || static_cast<size_t>(o.tool) >= tools) {
      throw std::invalid_argument(fmt::format("an observation refers to tool {}, but {} tool offset(s) were given", o.tool + 1, tools));
    }
    if (options.anchor == Anchor::kFirstTile && (o.group < 0 || o.group >= static_cast<int>(options.anchors.size()))) {
      throw std::invalid_argument("anchoring at the first tile needs a first tile for every measurement");
    }
  }
  return equations;
}

// Levenberg-Marquardt over the coefficients and the pose correction, in units of their plausible sizes, from and
// into `parameters` and `pose_parameters`; the solver's figures go into `result`.
void SolveScaled(const ParameterLayout& layout, const std::vector<Observation>& observations, const Prepared& prepared,
                 const IdentificationOptions& options, const Eigen::VectorXd& scale, std::vector<double>& parameters,
                 std::vector<double>& pose_parameters, IdentificationResult& result) {
  const int n = layout.NumFree();
  const int pose_count = static_cast<int>(pose_parameters.size());
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  // Blocks by group, cut into pieces that the solver's threads evaluate side by side (a tracker's thousands of
  // readings are one group), or one per observation.
  constexpr size_t kBlockSize = 256;
  std::map<std::pair<int, size_t>, std::vector<const PreparedObservation*>> blocks;
  std::map<int, size_t> group_size;
  for (size_t i = 0; i < prepared.observations.size(); ++i) {
    const int group = observations[i].group;
    const std::pair<int, size_t> key = options.loss == "none" ? std::make_pair(group, group_size[group]++ / kBlockSize)
                                                              : std::make_pair(static_cast<int>(i), size_t{0});
    blocks[key].push_back(&prepared.observations[i]);
  }
  std::vector<double*> blocks_of_parameters;
  if (n > 0) blocks_of_parameters.push_back(parameters.data());
  if (pose_count > 0) blocks_of_parameters.push_back(pose_parameters.data());
  if (blocks_of_parameters.empty()) {
    result.converged = true;
    return;
  }
  for (auto& [key, block] : blocks) {
    ceres::LossFunction* loss = nullptr;
    if (options.loss == "huber") loss = new ceres::HuberLoss(options.loss_scale_mm);
    if (options.loss == "cauchy") loss = new ceres::CauchyLoss(options.loss_scale_mm);
    problem.AddResidualBlock(new BlockCost(layout, scale, std::move(block), prepared), loss, blocks_of_parameters);
  }
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  // The start is the linearised least-squares solution and the model is nearly linear: begin as Gauss-Newton,
  // or the default damping crawls along the weakly determined directions for a dozen iterations.
  solver.initial_trust_region_radius = 1e12;
  solver.num_threads =
      options.num_threads > 0 ? options.num_threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  solver.function_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-10;
  solver.gradient_tolerance = 1e-14;
  // The iteration log reads the parameters as the solver leaves them after each step.
  std::unique_ptr<ceres::IterationCallback> log;
  if (options.on_iteration) {
    log = std::make_unique<IterationLog>([&] {
      std::vector<double> values(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) values[static_cast<size_t>(i)] = scale[i] * parameters[static_cast<size_t>(i)];
      std::array<double, kPoseParameters> pose6 = prepared.pose6;
      for (int i = 0; i < pose_count; ++i) pose6[static_cast<size_t>(i)] += prepared.pose_scale[i] * pose_parameters[static_cast<size_t>(i)];
      options.on_iteration(layout, values, Pose{Eigen::Vector3d(pose6[0], pose6[1], pose6[2]), Eigen::Vector3d(pose6[3], pose6[4], pose6[5])});
    });
    solver.update_state_every_iteration = true;
    solver.callbacks.push_back(log.get());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.solver_report = summary.BriefReport();
}

// Residual statistics and noise at the solution. The covariance uses the Jacobian of the rank analysis (at zero
// error): the model is linear in its coefficients to first order, and stage errors of 1e-3 change it by about
// 0.1 %, far below what a covariance estimated from tens of centres can resolve.
void JudgeSolution(const Prepared& prepared, const IdentificationOptions& options, const Eigen::VectorXd& scale,
                   const Eigen::MatrixXd& kept_normal, const std::array<double, kPoseParameters>& pose6, int equations,
                   int pose_count, IdentificationResult& result) {
  const ParameterLayout& layout = result.calibration.layout;
  const int n = layout.NumFree();
  Eigen::VectorXd whitened;
  Linearise(layout, result.calibration.values, pose6.data(), prepared, &whitened, nullptr);
  for (size_t i = 0; i < prepared.observations.size(); ++i) {
    const PreparedObservation& o = prepared.observations[i];
    result.residuals.push_back(o.colour * whitened.segment<3>(3 * static_cast<Eigen::Index>(i)));  // unobserved coordinates: 0
  }
  result.residual_summary = Summarize(result.residuals);
  const double dof = std::max(1.0, static_cast<double>(equations - n - pose_count));
  double plain_squared = 0.0;
  for (const Eigen::Vector3d& r : result.residuals) plain_squared += r.squaredNorm();
  result.calibration.sigma_mm = std::max(std::sqrt(plain_squared / dof), options.noise_floor_mm);
  result.weighted_rms = prepared.weighted ? std::sqrt(whitened.squaredNorm() / dof) : 0.0;
  const double factor = VarianceFactor(prepared.weighted, options.noise_floor_mm, whitened.squaredNorm(), dof);
  if (n + pose_count == 0) return;
  const auto eigen = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>>(kept_normal, "identification: the condition of the normal equations");
  const double lo = std::max(eigen.eigenvalues().minCoeff(), 0.0);
  result.condition_number = lo > 0 ? std::sqrt(eigen.eigenvalues().maxCoeff() / lo) : INFINITY;
  Eigen::VectorXd all_scale(n + pose_count);
  all_scale << scale, prepared.pose_scale.head(pose_count);
  const Eigen::MatrixXd covariance = factor * factor * (all_scale.asDiagonal() *
                                                        Decompose<Eigen::LDLT<Eigen::MatrixXd>>(kept_normal, "identification: the parameters' covariance")
                                                            .solve(Eigen::MatrixXd::Identity(n + pose_count, n + pose_count)) *
                                                        all_scale.asDiagonal());
  result.calibration.covariance = covariance.topLeftCorner(n, n);
  if (pose_count > 0) result.pose_covariance = covariance.bottomRightCorner<kPoseParameters, kPoseParameters>();
}

}  // namespace

IdentificationResult Identify(const ParameterLayout& input_layout, const std::vector<Observation>& observations,
                              const IdentificationOptions& options) {
  options.Check();
  const bool estimate_pose = options.instrument == InstrumentPose::kEstimated;
  const int pose_count = estimate_pose ? kPoseParameters : 0;
  const int equations = CountEquations(input_layout, observations, options, pose_count);

  IdentificationResult result(Calibration{"", input_layout, {}, {}, 0.0, std::nullopt, {}});
  if (!options.anchors.empty()) result.calibration.frame_reference = options.anchors.front();
  ParameterLayout& layout = result.calibration.layout;
  Prepared prepared = Prepare(layout, observations, options);
  const KeptStart start = TreatRank(layout, observations, prepared, options, equations, pose_count, result);
  for (const FixedCoefficient& f : result.fixed) layout.Fix(f.name, 0.0);
  Reslot(prepared, input_layout, layout);

  const Eigen::VectorXd scale = PlausibleSizes(layout);
  const int n = layout.NumFree();
  std::vector<double> parameters(start.parameters.begin(), start.parameters.end() - pose_count);
  parameters.resize(static_cast<size_t>(n), 0.0);
  std::vector<double> pose_parameters(start.parameters.end() - pose_count, start.parameters.end());
  pose_parameters.resize(static_cast<size_t>(pose_count), 0.0);
  SolveScaled(layout, observations, prepared, options, scale, parameters, pose_parameters, result);

  std::vector<double>& values = result.calibration.values;
  values.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) values[static_cast<size_t>(i)] = scale[i] * parameters[static_cast<size_t>(i)];
  std::array<double, kPoseParameters> pose6 = prepared.pose6;
  for (int i = 0; i < pose_count; ++i) pose6[static_cast<size_t>(i)] += prepared.pose_scale[i] * pose_parameters[static_cast<size_t>(i)];
  result.pose = options.instrument == InstrumentPose::kNone
                    ? Pose{}
                    : Pose{Eigen::Vector3d(pose6[0], pose6[1], pose6[2]), Eigen::Vector3d(pose6[3], pose6[4], pose6[5])};
  JudgeSolution(prepared, options, scale, start.normal, pose6, equations, pose_count, result);
  return result;
}

}  // namespace fvm::stage
