#include "stage/identification.h"

#include <ceres/ceres.h>
#include <fmt/core.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <map>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "stage/linear_dependence.h"
#include "stage/validation.h"

namespace fvm::stage {
namespace {

using SparseTermDerivative = std::vector<ParameterLayout::TermDerivativeEntry>;

// Forward model and, optionally, its Jacobian w.r.t. the free coefficients (3 x n, column-major) at one
// command: Jets through the chain for the 21 term values, then the exact linear map to the coefficients.
// `all` holds every coefficient's value (ParameterLayout::Expand), expanded once per evaluation, not per point.
Eigen::Vector3d EvaluatePoint(const ParameterLayout& layout, const double* all, const Eigen::Vector3d& q,
                              const SparseTermDerivative& derivative, Eigen::Matrix3Xd* jacobian) {
  double e[kNumErrorTerms];
  layout.TermValues(all, q, e);
  if (jacobian == nullptr) return ChainForward(layout.chain(), e, q);
  Eigen::Vector3d p;
  const Eigen::Matrix<double, 3, kNumErrorTerms> term_jacobian = TermJacobian(layout.chain(), e, q, &p, layout.AxesWithErrors());
  jacobian->setZero(3, layout.NumFree());
  for (const ParameterLayout::TermDerivativeEntry& d : derivative) jacobian->col(d.slot) += term_jacobian.col(d.term) * d.value;
  return p;
}

struct PreparedObservation {
  Eigen::Vector3d free;
  Eigen::Vector3d reference;
  SparseTermDerivative derivative;
  int anchor = -1;  // index into the prepared anchors, or -1
};

struct PreparedAnchor {
  Eigen::Vector3d position;
  SparseTermDerivative derivative;
};

// Observations as one Ceres residual block over the coefficients in units of their plausible size (coefficient =
// scale * parameter, so every parameter is of order one). A block holds one placement, whose first tile is then
// evaluated once, or a single observation when a robust loss must see each centre's error on its own.
class BlockCost final : public ceres::CostFunction {
 public:
  BlockCost(const ParameterLayout& layout, const Eigen::VectorXd& scale, std::vector<const PreparedObservation*> block,
            const std::vector<PreparedAnchor>& anchors)
      : layout_(layout), scale_(scale), block_(std::move(block)), anchors_(anchors) {
    set_num_residuals(3 * static_cast<int>(block_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(scale.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Index n = scale_.size();
    std::array<double, kMaxCoefficients> free{}, all{};
    for (Eigen::Index i = 0; i < n; ++i) free[static_cast<size_t>(i)] = scale_[i] * parameters[0][i];
    layout_.Expand(free.data(), all.data());
    const bool want_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    // The anchor term F(a) - a is common to the block (every observation of a block shares its anchor).
    Eigen::Vector3d anchor_shift = Eigen::Vector3d::Zero();
    Eigen::Matrix3Xd anchor_jacobian = Eigen::Matrix3Xd::Zero(3, n);
    if (block_.front()->anchor >= 0) {
      const PreparedAnchor& a = anchors_[static_cast<size_t>(block_.front()->anchor)];
      anchor_shift = EvaluatePoint(layout_, all.data(), a.position, a.derivative, want_jacobian ? &anchor_jacobian : nullptr) - a.position;
    }
    Eigen::Matrix3Xd jacobian;
    for (size_t k = 0; k < block_.size(); ++k) {
      const PreparedObservation& o = *block_[k];
      const Eigen::Vector3d r =
          EvaluatePoint(layout_, all.data(), o.free, o.derivative, want_jacobian ? &jacobian : nullptr) - anchor_shift - o.reference;
      for (int c = 0; c < 3; ++c) residuals[3 * k + static_cast<size_t>(c)] = r[c];
      if (want_jacobian) {
        Eigen::Map<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>> out(jacobians[0] + 3 * k * static_cast<size_t>(n), 3, n);
        out = (jacobian - anchor_jacobian) * scale_.asDiagonal();
      }
    }
    return true;
  }

 private:
  const ParameterLayout& layout_;
  const Eigen::VectorXd& scale_;
  std::vector<const PreparedObservation*> block_;
  const std::vector<PreparedAnchor>& anchors_;
};

// Order in which coefficients are kept when the data cannot tell some apart: lower powers first; within a
// power, translations (positioning, straightness), then squareness, then yaw, then pitch and roll, whose effect
// needs a height change that a flat artefact hardly gives.
std::vector<int> KeepingOrder(const ParameterLayout& layout) {
  const auto rank = [&](int slot) {
    const ParameterLayout::Coefficient& c =
        layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(slot)]))];
    const ErrorTerm& term = GetErrorTerm(c.term);
    int kind = 0;
    if (term.kind == ErrorKind::kSquareness) kind = 1;
    if (term.kind == ErrorKind::kRotation) kind = term.component == 2 ? 2 : 3;
    return std::make_tuple(c.power, kind, slot);
  };
  std::vector<int> order(static_cast<size_t>(layout.NumFree()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return rank(a) < rank(b); });
  return order;
}

const ParameterLayout::Coefficient& FreeCoefficient(const ParameterLayout& layout, int slot) {
  return layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(slot)]))];
}

std::string FormatValue(const ParameterLayout::Coefficient& c, double si) {
  const DisplayUnit unit = UnitOf(c);
  return fmt::format("{:.3g} {}", si * unit.per_si, unit.name);
}

struct Prepared {
  std::vector<PreparedObservation> observations;
  std::vector<PreparedAnchor> anchors;
};

Prepared Prepare(const ParameterLayout& layout, const std::vector<Observation>& observations,
                 const IdentificationOptions& options) {
  Prepared p;
  if (options.anchor == Anchor::kFirstTile) {
    for (const Eigen::Vector3d& a : options.anchors) p.anchors.push_back({a, layout.TermDerivativeEntries(a)});
  }
  for (const Observation& o : observations) {
    PreparedObservation po{o.free, o.reference, layout.TermDerivativeEntries(o.free), -1};
    if (options.anchor == Anchor::kFirstTile) po.anchor = o.group;
    p.observations.push_back(std::move(po));
  }
  return p;
}

// Stacked residuals and, unless `jacobian` is null, their Jacobian (unscaled) at the given coefficients.
void Linearise(const ParameterLayout& layout, const std::vector<double>& free, const Prepared& p,
               Eigen::VectorXd* residual, Eigen::MatrixXd* jacobian) {
  const Eigen::Index m = static_cast<Eigen::Index>(p.observations.size());
  std::array<double, kMaxCoefficients> all{};
  layout.Expand(free.data(), all.data());
  residual->resize(3 * m);
  if (jacobian) jacobian->resize(3 * m, layout.NumFree());
  std::vector<Eigen::Vector3d> anchor_shift;
  std::vector<Eigen::Matrix3Xd> anchor_jacobian(p.anchors.size());
  for (size_t a = 0; a < p.anchors.size(); ++a) {
    anchor_shift.push_back(EvaluatePoint(layout, all.data(), p.anchors[a].position, p.anchors[a].derivative,
                                         jacobian ? &anchor_jacobian[a] : nullptr) -
                           p.anchors[a].position);
  }
  Eigen::Matrix3Xd j;
  for (Eigen::Index i = 0; i < m; ++i) {
    const PreparedObservation& o = p.observations[static_cast<size_t>(i)];
    residual->segment<3>(3 * i) = EvaluatePoint(layout, all.data(), o.free, o.derivative, jacobian ? &j : nullptr) - o.reference;
    if (o.anchor >= 0) residual->segment<3>(3 * i) -= anchor_shift[static_cast<size_t>(o.anchor)];
    if (!jacobian) continue;
    if (o.anchor >= 0) j -= anchor_jacobian[static_cast<size_t>(o.anchor)];
    jacobian->middleRows<3>(3 * i) = j;
  }
}

}  // namespace

void IdentificationOptions::Check() const {
  if (loss != "none" && loss != "huber" && loss != "cauchy") {
    throw std::invalid_argument("unknown loss '" + loss + "': use none, huber or cauchy");
  }
  if (num_threads < 0) throw std::invalid_argument("num_threads must be 0 (all cores) or positive");
  if (!(loss_scale_mm > 0) || !(alias_tolerance > 0) || !(max_relative_uncertainty > 0) || !(noise_floor_mm > 0)) {
    throw std::invalid_argument("identification tolerances must be positive");
  }
}

Eigen::Vector3d FirstTile(const std::vector<Eigen::Vector3d>& positions) {
  if (positions.empty()) throw std::invalid_argument("a measurement without points has no first tile");
  Eigen::Vector2d corner = positions[0].head<2>();
  for (const Eigen::Vector3d& p : positions) corner = Eigen::Vector2d(std::min(corner.x(), p.x()), std::max(corner.y(), p.y()));
  // Its height is that of the part under it: the point nearest the corner (a tilted part is not at its mean z there).
  const Eigen::Vector3d* nearest = &positions[0];
  for (const Eigen::Vector3d& p : positions) {
    if ((p.head<2>() - corner).squaredNorm() < (nearest->head<2>() - corner).squaredNorm()) nearest = &p;
  }
  return Eigen::Vector3d(corner.x(), corner.y(), nearest->z());
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

Eigen::Vector3d ModelResidual(const ParameterLayout& layout, const double* free, const Observation& observation,
                              const Eigen::Vector3d* anchor) {
  Eigen::Vector3d r = Forward(layout, free, Eigen::Vector3d(observation.free)) - observation.reference;
  if (anchor) r -= Forward(layout, free, Eigen::Vector3d(*anchor)) - *anchor;
  return r;
}

IdentificationResult Identify(const ParameterLayout& input_layout, const std::vector<Observation>& observations,
                              const IdentificationOptions& options) {
  options.Check();
  const int m = static_cast<int>(observations.size());
  if (3 * m < input_layout.NumFree()) {
    throw std::invalid_argument(fmt::format(
        "{} centres give {} equations, fewer than the {} coefficients of the model: measure more placements or "
        "choose a smaller model", m, 3 * m, input_layout.NumFree()));
  }
  if (options.anchor == Anchor::kFirstTile) {
    for (const Observation& o : observations) {
      if (o.group < 0 || o.group >= static_cast<int>(options.anchors.size())) {
        throw std::invalid_argument("anchoring at the first tile needs a first tile for every measurement");
      }
    }
  }

  IdentificationResult result(Calibration{"", input_layout, {}, {}, 0.0});
  ParameterLayout& layout = result.calibration.layout;
  Prepared prepared = Prepare(layout, observations, options);

  std::vector<double> start_parameters;  // in units of the plausible sizes, for the kept coefficients
  Eigen::MatrixXd kept_normal;           // J^T J of the kept coefficients in those units, at zero error
  // Rank treatment on the Jacobian at zero error (the model is linear in its coefficients to first order).
  {
    const std::vector<double> zeros(static_cast<size_t>(layout.NumFree()), 0.0);
    Eigen::VectorXd r0;
    Eigen::MatrixXd j;
    Linearise(layout, zeros, prepared, &r0, &j);
    const Eigen::VectorXd tau = PlausibleSizes(layout);
    j.array().rowwise() *= tau.transpose().array();  // columns in units of the plausible sizes
    const Eigen::VectorXd gradient = j.transpose() * r0;
    // R of j = QR has the column geometry of j in n x n: search dependences and form normal equations there.
    // (In place: j is large, 3 rows per centre.)
    const Eigen::Index n_all = j.cols();
    const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(j);
    const Eigen::MatrixXd r_factor = qr.matrixQR().topRows(n_all).triangularView<Eigen::Upper>();
    const std::vector<std::string> names = layout.FreeNames();
    std::vector<bool> fixed(names.size(), false);

    const std::vector<int> keeping_order = KeepingOrder(layout);
    std::vector<int> rank_of(names.size());
    for (size_t i = 0; i < keeping_order.size(); ++i) rank_of[static_cast<size_t>(keeping_order[i])] = static_cast<int>(i);
    for (const ColumnDependence& d : FindDependentColumns(r_factor, keeping_order, options.alias_tolerance)) {
      fixed[static_cast<size_t>(d.column)] = true;
      std::string why;
      if (d.on.empty()) {
        why = options.anchor == Anchor::kFirstTile
                  ? "no effect on these data: anchoring every measurement at its first tile cancels it"
                  : "no effect on these data";
      } else {
        why = "same effect as";
        for (size_t k = 0; k < d.on.size(); ++k) {
          const auto [other, factor] = d.on[k];
          why += fmt::format("{} {:.4g} * {}", k ? " +" : "", factor * tau[other] / tau[d.column],
                             names[static_cast<size_t>(other)]);
        }
        why += " on these data";
      }
      result.fixed.push_back({names[static_cast<size_t>(d.column)], why});
    }

    // Weakly determined coefficients: fix the worst while one's standard uncertainty, in units of its
    // plausible size, exceeds the limit. Normal equations on scaled columns are well enough conditioned here.
    const Eigen::MatrixXd normal = r_factor.transpose() * r_factor;
    const double r0_squared = r0.squaredNorm();
    Eigen::VectorXd start;
    while (true) {
      std::vector<int> kept;
      for (size_t c = 0; c < fixed.size(); ++c) {
        if (!fixed[c]) kept.push_back(static_cast<int>(c));
      }
      const Eigen::Index k = static_cast<Eigen::Index>(kept.size());
      if (k == 0) break;
      Eigen::MatrixXd nk(k, k);
      Eigen::VectorXd gk(k);
      for (Eigen::Index a = 0; a < k; ++a) {
        gk[a] = gradient[kept[static_cast<size_t>(a)]];
        for (Eigen::Index b = 0; b < k; ++b) nk(a, b) = normal(kept[static_cast<size_t>(a)], kept[static_cast<size_t>(b)]);
      }
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(nk);
      start = -ldlt.solve(gk);  // the linearised least-squares solution: where LM starts
      const double rss = std::max(0.0, r0_squared - gk.dot(ldlt.solve(gk)));
      const double dof = std::max(1.0, 3.0 * m - static_cast<double>(k));
      const double sigma = std::max(std::sqrt(rss / dof), options.noise_floor_mm);
      const Eigen::MatrixXd covariance = sigma * sigma * ldlt.solve(Eigen::MatrixXd::Identity(k, k));
      // Of the coefficients the data cannot determine, fix the one we would keep last (KeepingOrder): when
      // pitch and a squareness term explain the same thing, the squareness stays.
      Eigen::Index worst = -1;
      for (Eigen::Index a = 0; a < k; ++a) {
        const double u = std::sqrt(std::max(0.0, covariance(a, a)));
        if (!(u <= options.max_relative_uncertainty)) {
          if (worst < 0 || rank_of[static_cast<size_t>(kept[static_cast<size_t>(a)])] >
                               rank_of[static_cast<size_t>(kept[static_cast<size_t>(worst)])]) {
            worst = a;
          }
        }
      }
      if (worst < 0) {
        start_parameters.assign(start.data(), start.data() + start.size());
        kept_normal = nk;
        break;
      }
      const double u = std::sqrt(std::max(0.0, covariance(worst, worst)));
      const int column = kept[static_cast<size_t>(worst)];
      Eigen::Index partner = worst == 0 ? 1 : 0;  // the kept coefficient it is most correlated with
      for (Eigen::Index a = 0; a < k; ++a) {
        if (a == worst) continue;
        const double rho = std::abs(covariance(worst, a)) / std::sqrt(covariance(a, a) * covariance(worst, worst));
        const double best = std::abs(covariance(worst, partner)) / std::sqrt(covariance(partner, partner) * covariance(worst, worst));
        if (rho > best) partner = a;
      }
      const ParameterLayout::Coefficient& c = FreeCoefficient(layout, column);
      std::string why = fmt::format(
          "undetermined by these data: its standard uncertainty would be {}, {:.0f}% of a plausible {}", FormatValue(c, u * tau[column]),
          100.0 * u, FormatValue(c, tau[column]));
      if (k > 1) {
        const double rho = covariance(worst, partner) / std::sqrt(covariance(partner, partner) * covariance(worst, worst));
        why += fmt::format(" (correlation {:+.3f} with {})", rho, names[static_cast<size_t>(kept[static_cast<size_t>(partner)])]);
      }
      const ErrorTerm& term = GetErrorTerm(c.term);
      if (term.kind == ErrorKind::kRotation && term.component != 2) why += "; pitch and roll need height changes";
      result.fixed.push_back({names[static_cast<size_t>(column)], why});
      fixed[static_cast<size_t>(column)] = true;
    }
  }
  for (const FixedCoefficient& f : result.fixed) layout.Fix(f.name, 0.0);
  prepared = Prepare(layout, observations, options);

  // Levenberg-Marquardt over the coefficients in units of their plausible size.
  const Eigen::VectorXd scale = PlausibleSizes(layout);
  const int n = layout.NumFree();
  std::vector<double> parameters = start_parameters;
  parameters.resize(static_cast<size_t>(n), 0.0);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::map<int, std::vector<const PreparedObservation*>> blocks;  // by group, or one per observation
  for (size_t i = 0; i < prepared.observations.size(); ++i) {
    const int key = options.loss == "none" ? observations[i].group : static_cast<int>(i);
    blocks[key].push_back(&prepared.observations[i]);
  }
  for (auto& [key, block] : blocks) {
    ceres::LossFunction* loss = nullptr;
    if (options.loss == "huber") loss = new ceres::HuberLoss(options.loss_scale_mm);
    if (options.loss == "cauchy") loss = new ceres::CauchyLoss(options.loss_scale_mm);
    if (n > 0) problem.AddResidualBlock(new BlockCost(layout, scale, std::move(block), prepared.anchors), loss, parameters.data());
  }
  if (n > 0) {
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
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    result.iterations = static_cast<int>(summary.iterations.size());
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.solver_report = summary.BriefReport();
  } else {
    result.converged = true;
  }

  std::vector<double>& values = result.calibration.values;
  values.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) values[static_cast<size_t>(i)] = scale[i] * parameters[static_cast<size_t>(i)];

  // Residual statistics and noise at the solution. The covariance uses the Jacobian of the rank analysis (at
  // zero error): the model is linear in its coefficients to first order, and stage errors of 1e-3 change it by
  // about 0.1 %, far below what a covariance estimated from tens of centres can resolve.
  Eigen::VectorXd r;
  Linearise(layout, values, prepared, &r, nullptr);
  for (int i = 0; i < m; ++i) result.residuals.push_back(r.segment<3>(3 * i));
  const ResidualSummary summary = Summarize(result.residuals);
  result.mean_mm = summary.mean_mm;
  result.rms_mm = summary.rms_mm;
  result.max_mm = summary.max_mm;
  const double dof = std::max(1.0, 3.0 * m - n);
  result.calibration.sigma_mm = std::max(std::sqrt(r.squaredNorm() / dof), options.noise_floor_mm);
  if (n > 0) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(kept_normal);
    const double lo = std::max(eigen.eigenvalues().minCoeff(), 0.0);
    result.condition_number = lo > 0 ? std::sqrt(eigen.eigenvalues().maxCoeff() / lo) : INFINITY;
    const Eigen::MatrixXd scaled_cov = kept_normal.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    result.calibration.covariance = result.calibration.sigma_mm * result.calibration.sigma_mm *
                                    (scale.asDiagonal() * scaled_cov * scale.asDiagonal());
  }
  return result;
}

}  // namespace fvm::stage
