#include "imaging/sphere_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "core/dense_decomposition.h"
#include "core/input_error.h"
#include "core/statistics.h"
#include "imaging/sample_consensus.h"

namespace fvm::imaging {
namespace {

// Below this |n_z| the height residual stops growing (kHeight): 84 degrees of slope, steeper than any
// focus-variation instrument measures, so the floor only guards the arithmetic.
constexpr double kMinNormalZ = 0.1;

// Sets larger than twice this are fitted on a subsample first (see FitSphere).
constexpr std::size_t kCoarsePoints = 50000;

// The residual of one point and its derivatives with respect to (centre, radius), for both residual kinds, with
// q = p - c already formed. Exact derivatives: the height weight d/|q_z| depends on the centre too.
struct PointResidual {
  double value;
  Eigen::Vector4d jacobian;  // d value / d (cx, cy, cz, r)
  double deviation;          // |q| - r, what the instrument reports whichever residual is fitted
};

inline PointResidual EvaluatePoint(const Eigen::Vector3d& q, double radius, SphereResidual kind) {
  // One division per point (divisions cost several multiplications each, and this runs a million times a pass).
  const double d = q.norm();
  const double inv_d = 1.0 / d;
  const Eigen::Vector3d u = q * inv_d;
  const double r = d - radius;
  if (kind == SphereResidual::kOrthogonal) return {r, Eigen::Vector4d(-u.x(), -u.y(), -u.z(), -1.0), r};
  const double abs_qz = std::abs(q.z());
  if (abs_qz < kMinNormalZ * d) {
    const double w = 1.0 / kMinNormalZ;
    return {w * r, Eigen::Vector4d(-w * u.x(), -w * u.y(), -w * u.z(), -w), r};
  }
  // value = r d / |q_z|; d/dc of d is -u, of |q_z| is -sign(q_z) e_z.
  const double inv_qz = 1.0 / abs_qz;  // the second division, for the height residual only
  const double w = d * inv_qz;
  Eigen::Vector4d j;
  j.head<3>() = -(2.0 * d - radius) * inv_qz * u;
  j.z() += (q.z() > 0 ? r : -r) * w * inv_qz;  // r d sign(q_z) / q_z^2
  j.w() = -w;
  return {w * r, j, r};
}

// Ceres' view of the same residual, templated for automatic derivatives.
struct SphereResidualCost {
  SphereResidualCost(const Eigen::Vector3d& point, SphereResidual kind) : point(point), kind(kind) {}

  template <typename T>
  bool operator()(const T* const centre, const T* const radius, T* residual) const {
    const T qx = T(point.x()) - centre[0];
    const T qy = T(point.y()) - centre[1];
    const T qz = T(point.z()) - centre[2];
    const T d = ceres::sqrt(qx * qx + qy * qy + qz * qz);
    residual[0] = d - radius[0];
    if (kind == SphereResidual::kHeight) {
      const T abs_qz = ceres::abs(qz);
      residual[0] *= abs_qz < kMinNormalZ * d ? T(1.0 / kMinNormalZ) : d / abs_qz;
    }
    return true;
  }

  Eigen::Vector3d point;
  SphereResidual kind;
};

std::string PointsNeeded(bool fixed_radius) {
  return fixed_radius ? "4 points (3 unknowns and one more to estimate the noise)"
                      : "5 points (4 unknowns and one more to estimate the noise)";
}

// The normal equations of the selected points at a parameter vector, and their deviation statistics, summed in
// one pass.
struct NormalEquations {
  Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
  Eigen::Vector4d jtr = Eigen::Vector4d::Zero();
  double cost = 0.0;  // sum of squared residuals
  std::size_t count = 0;
  double min_deviation = 0.0, max_deviation = 0.0, sum_deviation = 0.0, sum_deviation2 = 0.0;
};

// Which points a pass sums: those of a mask, or (trimming) those whose residual at this very parameter vector
// is within a threshold, which it writes to a new mask, so that trimming costs no pass of its own.
struct Selection {
  const std::vector<bool>* mask = nullptr;
  double threshold = 0.0;                // with `trimmed`: keep |residual| <= threshold
  std::vector<bool>* trimmed = nullptr;  // the new mask
  std::size_t changed = 0;               // points whose membership differs from `mask`
};

NormalEquations Accumulate(std::span<const Eigen::Vector3d> points, Selection& select, const Eigen::Vector3d& origin,
                           const Eigen::Vector4d& theta, SphereResidual kind) {
  // Ten products of the symmetric 4 x 4 in scalars: Eigen's rank update on a Matrix4d would touch all 16.
  double a00 = 0, a01 = 0, a02 = 0, a03 = 0, a11 = 0, a12 = 0, a13 = 0, a22 = 0, a23 = 0, a33 = 0;
  double b0 = 0, b1 = 0, b2 = 0, b3 = 0, cost = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0, sum2 = 0;
  std::size_t count = 0, changed = 0;
  const std::vector<bool>& mask = *select.mask;
  const Eigen::Vector3d c = origin + theta.head<3>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!select.trimmed && !mask[i]) continue;
    const PointResidual e = EvaluatePoint(points[i] - c, theta.w(), kind);
    if (select.trimmed) {
      const bool keep = std::abs(e.value) <= select.threshold;
      (*select.trimmed)[i] = keep;
      changed += keep != mask[i];
      if (!keep) continue;
    }
    const double j0 = e.jacobian[0], j1 = e.jacobian[1], j2 = e.jacobian[2], j3 = e.jacobian[3];
    a00 += j0 * j0, a01 += j0 * j1, a02 += j0 * j2, a03 += j0 * j3;
    a11 += j1 * j1, a12 += j1 * j2, a13 += j1 * j3;
    a22 += j2 * j2, a23 += j2 * j3, a33 += j3 * j3;
    b0 += j0 * e.value, b1 += j1 * e.value, b2 += j2 * e.value, b3 += j3 * e.value;
    cost += e.value * e.value;
    lo = std::min(lo, e.deviation), hi = std::max(hi, e.deviation);
    sum += e.deviation, sum2 += e.deviation * e.deviation;
    ++count;
  }
  select.changed = changed;
  NormalEquations n;
  n.jtj << a00, a01, a02, a03, a01, a11, a12, a13, a02, a12, a22, a23, a03, a13, a23, a33;
  n.jtr << b0, b1, b2, b3;
  n.cost = cost;
  n.count = count;
  n.min_deviation = lo, n.max_deviation = hi, n.sum_deviation = sum, n.sum_deviation2 = sum2;
  return n;
}

NormalEquations Accumulate(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask,
                           const Eigen::Vector3d& origin, const Eigen::Vector4d& theta, SphereResidual kind) {
  Selection select{&mask};
  return Accumulate(points, select, origin, theta, kind);
}

struct SolveResult {
  Eigen::Vector4d theta = Eigen::Vector4d::Zero();  // centre relative to the origin, radius
  NormalEquations normal;                           // at theta
  int iterations = 0;
  bool converged = false;
  std::string stop_reason;
};

// Levenberg-Marquardt on the normal equations; one pass over the points per iteration (the pass at the trial
// point gives both its cost and, when accepted, the next normal equations). It has converged when the undamped
// (Gauss-Newton) step, the distance to the minimum of the local quadratic, would move no parameter by more than
// 1e-3 of its standard deviation (or 1e-12 of the cap's size, for noise-free data): further passes would change
// nothing a user could see, and at a million points each costs ~6 ms. The test is on the undamped step: a damped
// step is small because lambda is large, not because the minimum is near. When no damped step lowers the cost,
// it is at the minimum only if that step is within 1e-2 of a standard deviation (the cost's rounding can hide
// smaller improvements); otherwise it is stuck, and says so.
SolveResult SolveNormalEquations(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask,
                                 const Eigen::Vector3d& origin, const Eigen::Vector4d& start,
                                 const NormalEquations& at_start, double scale, const SphereFitOptions& options) {
  const bool fixed = options.fixed_radius_mm > 0;
  const int n = fixed ? 3 : 4;
  SolveResult out;
  out.theta = start;
  NormalEquations current = at_start;
  double lambda = 1e-6;
  for (int it = 0; it < options.max_iterations; ++it) {
    ++out.iterations;
    const Eigen::MatrixXd jtj = current.jtj.topLeftCorner(n, n);
    const Eigen::VectorXd jtr = current.jtr.head(n);
    const double variance = current.cost / std::max(1.0, static_cast<double>(current.count) - n);
    const auto undamped = Decompose<Eigen::LDLT<Eigen::MatrixXd>>(jtj, "the sphere fit: its normal equations");
    const Eigen::VectorXd sd = (variance * undamped.solve(Eigen::MatrixXd::Identity(n, n)).diagonal()).cwiseAbs().cwiseSqrt();
    const Eigen::VectorXd newton = -undamped.solve(jtr);
    const auto within = [&](double fraction) {
      return newton.allFinite() && (newton.cwiseAbs().array() <= (fraction * sd.array()).max(1e-12 * scale)).all();
    };
    if (within(1e-3)) {
      out.converged = true;
      out.stop_reason = "at the minimum";
      out.normal = current;
      return out;
    }
    bool accepted = false;
    while (lambda < 1e16) {
      Eigen::MatrixXd damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::VectorXd step = -Decompose<Eigen::LDLT<Eigen::MatrixXd>>(damped, "the sphere fit: a damped step").solve(jtr);
      if (!step.allFinite()) {
        lambda *= 10;
        continue;
      }
      Eigen::Vector4d trial = out.theta;
      trial.head(n) += step;
      NormalEquations next = Accumulate(points, mask, origin, trial, options.residual);
      if (next.cost <= current.cost) {
        out.theta = trial;
        current = next;
        lambda = std::max(lambda * 0.1, 1e-12);
        accepted = true;
        break;
      }
      lambda *= 10;
    }
    if (!accepted) {
      out.converged = within(1e-2);
      out.stop_reason = out.converged ? "at the minimum (no step lowers the cost further)"
                                      : "stuck: no step lowers the cost, but the Gauss-Newton step is not small";
      out.normal = current;
      return out;
    }
  }
  out.stop_reason = "iteration limit (" + std::to_string(options.max_iterations) + ") reached";
  out.normal = current;
  return out;
}

// Ceres is the reference; its solution gets a pass of ours for the normal equations the result is read from.
SolveResult SolveCeres(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask,
                       const Eigen::Vector3d& origin, const Eigen::Vector4d& start, const SphereFitOptions& options) {
  double centre[3] = {start.x(), start.y(), start.z()};
  double radius = start.w();
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SphereResidualCost, 1, 3, 1>(
                                 new SphereResidualCost(points[i] - origin, options.residual)),
                             nullptr, centre, &radius);
  }
  if (options.fixed_radius_mm > 0) problem.SetParameterBlockConstant(&radius);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-15;
  solver_options.gradient_tolerance = 1e-20;
  solver_options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  SolveResult out;
  out.theta = Eigen::Vector4d(centre[0], centre[1], centre[2], radius);
  out.normal = Accumulate(points, mask, origin, out.theta, options.residual);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.stop_reason = out.converged ? "at the minimum" : "Ceres: " + summary.message;
  return out;
}

struct Algebraic {
  Sphere sphere;
  Eigen::Vector3d origin;  // a point of the set: coordinates relative to it keep their digits
  double spread;           // RMS distance of the points from their mean
};

// The algebraic fit of the masked points (see FitSphereAlgebraic), in one pass: the sums are formed relative to
// the first point (so stage coordinates of -150 mm cost no digits), and the 4 x 4 system is equilibrated
// before it is solved, so that its rank test does not depend on the calotte's size.
Algebraic AlgebraicFit(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask) {
  std::size_t first = 0;
  while (first < points.size() && !mask[first]) ++first;
  const Eigen::Vector3d origin = first < points.size() ? points[first] : Eigen::Vector3d::Zero();
  double sxx = 0, sxy = 0, sxz = 0, sx = 0, syy = 0, syz = 0, sy = 0, szz = 0, sz = 0;
  double bx = 0, by = 0, bz = 0, b1 = 0;
  std::size_t count = 0;
  for (std::size_t i = first; i < points.size(); ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector3d q = points[i] - origin;
    const double x = q.x(), y = q.y(), z = q.z(), r2 = q.squaredNorm();
    sxx += x * x, sxy += x * y, sxz += x * z, sx += x;
    syy += y * y, syz += y * z, sy += y;
    szz += z * z, sz += z;
    bx += x * r2, by += y * r2, bz += z * r2, b1 += r2;
    ++count;
  }
  if (count < 4) {
    throw InputError("sphere fit: " + std::to_string(count) +
                     " points cannot determine a sphere; it takes at least 4 (not on one plane)");
  }
  const double m = static_cast<double>(count);
  const Eigen::Vector3d mean(sx / m, sy / m, sz / m);
  const double spread = std::sqrt(std::max(0.0, b1 / m - mean.squaredNorm()));
  if (!(spread > 0)) throw InputError("sphere fit: all points coincide; no sphere passes through them");
  // |q|^2 = 2 c.q + k with unknowns (2 c, k).
  Eigen::Matrix4d ata;
  ata << sxx, sxy, sxz, sx, sxy, syy, syz, sy, sxz, syz, szz, sz, sx, sy, sz, m;
  const Eigen::Vector4d atb(bx, by, bz, b1);
  const Eigen::Vector4d d = ata.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::Matrix4d equilibrated = d.asDiagonal() * ata * d.asDiagonal();
  const auto lu = Decompose<Eigen::FullPivLU<Eigen::Matrix4d>>(equilibrated, "the algebraic sphere fit");
  if (lu.rank() < 4 || lu.rcond() < 1e-12) {
    throw InputError("sphere fit: the " + std::to_string(count) +
                     " points lie on a plane or a line; they do not determine a sphere");
  }
  const Eigen::Vector4d x = d.asDiagonal() * lu.solve(d.asDiagonal() * atb);
  const Eigen::Vector3d c = 0.5 * x.head<3>();
  return Algebraic{Sphere{origin + c, std::sqrt(std::max(0.0, x.w() + c.squaredNorm()))}, origin, spread};
}

// Seeded MSAC on spheres through 4 points (or, kLeastMedian, the least median of squares), scored on at most
// 2000 points (the score only ranks hypotheses; the consensus set is then taken over all points).
std::vector<bool> RansacInliers(std::span<const Eigen::Vector3d> points, const SphereFitOptions& options) {
  const bool least_median = options.outliers == SphereOutliers::kLeastMedian;
  const auto through = [&](const std::array<Eigen::Vector3d, 4>& sample) -> std::optional<Sphere> {
    Sphere s;
    try {
      s = AlgebraicFit(sample, std::vector<bool>(4, true)).sphere;
    } catch (const InputError&) {
      return std::nullopt;  // a degenerate sample (coplanar points)
    }
    if (!std::isfinite(s.radius_mm)) return std::nullopt;
    if (options.fixed_radius_mm > 0 && std::abs(s.radius_mm - options.fixed_radius_mm) > 0.2 * options.fixed_radius_mm) {
      return std::nullopt;
    }
    return s;
  };
  const auto distance = [](const Sphere& s, const Eigen::Vector3d& p) { return (p - s.centre_mm).norm() - s.radius_mm; };
  const ConsensusSearch<Sphere> search = SearchConsensus<4, Sphere>(
      points, options.seed, options.ransac_iterations, least_median ? std::nullopt : std::optional<double>(options.inlier_threshold_mm), through,
      distance);
  if (!search.best) {
    throw InputError("sphere fit: no 4 of the points span a sphere; the points lie on a plane or a line");
  }
  // Least median: points within 2.5 robust standard deviations of the best sphere are the consensus set.
  const double t = least_median ? LeastMedianThreshold(search.score, search.scored_points, 4, options.min_threshold_mm)
                                : options.inlier_threshold_mm;
  std::vector<bool> inlier(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) inlier[i] = std::abs(distance(*search.best, points[i])) <= t;
  return inlier;
}

}  // namespace

void SphereFitOptions::Check() const {
  if (!(fixed_radius_mm >= 0) || !std::isfinite(fixed_radius_mm)) {
    throw std::invalid_argument("sphere fit: the fixed radius must be positive (or 0 to estimate it)");
  }
  if (!(outlier_sigmas > 0) || !(min_threshold_mm >= 0) || !(inlier_threshold_mm >= 0)) {
    throw std::invalid_argument("sphere fit: outlier thresholds must be positive");
  }
  if (outliers == SphereOutliers::kRansac && !(inlier_threshold_mm > 0)) {
    throw std::invalid_argument("sphere fit: RANSAC needs an inlier threshold (inlier_threshold_mm > 0)");
  }
  if (max_iterations < 1 || max_trim_rounds < 0 || ransac_iterations < 1) {
    throw std::invalid_argument("sphere fit: iteration limits must be positive");
  }
}

Sphere FitSphereAlgebraic(std::span<const Eigen::Vector3d> points) {
  return AlgebraicFit(points, std::vector<bool>(points.size(), true)).sphere;
}

SphereFit FitSphere(std::span<const Eigen::Vector3d> points, const SphereFitOptions& options) {
  options.Check();
  const bool fixed = options.fixed_radius_mm > 0;
  const int n = fixed ? 3 : 4;
  if (points.size() < static_cast<std::size_t>(n + 1)) {
    throw InputError("sphere fit: " + std::to_string(points.size()) + " points are too few; it takes at least " +
                     PointsNeeded(fixed));
  }
  for (const auto& p : points) {
    if (!p.allFinite()) throw InputError("sphere fit: a point is NaN or infinite; leave invalid points out");
  }

  SphereFit fit;
  fit.points = points.size();
  fit.inlier.assign(points.size(), true);
  Eigen::Vector3d origin;
  Eigen::Vector4d theta;
  double scale = 0.0;
  // Coarse to fine: a large set is first fitted on an even subsample (start, consensus, trimming and all), so
  // that the passes over every point start next to the solution: one Gauss-Newton step and one trimming pass
  // usually settle it. The result is still the least-squares fit to all points; only the passes are saved.
  const bool coarse = points.size() > 2 * kCoarsePoints && options.solver == SphereSolver::kNormalEquations;
  if (coarse) {
    const std::size_t stride = points.size() / kCoarsePoints;
    std::vector<Eigen::Vector3d> subsample;
    subsample.reserve(points.size() / stride + 1);
    for (std::size_t i = 0; i < points.size(); i += stride) subsample.push_back(points[i]);
    const SphereFit start = FitSphere(subsample, options);
    origin = points[0];
    theta << start.centre_mm - origin, start.radius_mm;
    scale = start.radius_mm;
  } else {
    if (options.outliers == SphereOutliers::kRansac || options.outliers == SphereOutliers::kLeastMedian) {
      fit.inlier = RansacInliers(points, options);
      const auto agree = static_cast<std::size_t>(std::count(fit.inlier.begin(), fit.inlier.end(), true));
      if (agree < static_cast<std::size_t>(n + 1)) {
        throw InputError("sphere fit: only " + std::to_string(agree) +
                         " points agree with any sphere within the inlier threshold; it takes at least " +
                         PointsNeeded(fixed));
      }
    }
    // Work relative to one of the points: stage coordinates of -150 mm would otherwise cost digits.
    const Algebraic start = AlgebraicFit(points, fit.inlier);
    origin = start.origin;
    theta << start.sphere.centre_mm - origin, fixed ? options.fixed_radius_mm : start.sphere.radius_mm;
    scale = start.spread;
  }

  std::vector<bool> next(points.size());
  // One pass: the residuals at theta decide the inliers and the same pass sums their normal equations (left in
  // *trimmed, consistent with the new inliers). Returns how many points changed side.
  const auto trim = [&](NormalEquations* trimmed) -> std::size_t {
    double threshold = options.inlier_threshold_mm;
    if (threshold <= 0) {
      // The median absolute residual of the current inliers: residuals of a least-squares fit centre on zero,
      // and the median ignores the outliers it is meant to find (up to half of them). Every k-th inlier is
      // plenty (100 000 give the median to 0.4 %) and spares a million-point fit a buffer of residuals.
      const Eigen::Vector3d c = origin + theta.head<3>();
      const std::size_t stride = std::max<std::size_t>(1, points.size() / 100000);
      std::vector<double> sample;
      sample.reserve(points.size() / stride + 1);
      for (std::size_t i = 0; i < points.size(); i += stride) {
        if (fit.inlier[i]) sample.push_back(std::abs(EvaluatePoint(points[i] - c, theta.w(), options.residual).value));
      }
      threshold = std::max(options.outlier_sigmas * 1.4826 * HighMedian(std::move(sample)), options.min_threshold_mm);
    }
    Selection select{&fit.inlier, threshold, &next};
    *trimmed = Accumulate(points, select, origin, theta, options.residual);
    if (trimmed->count < static_cast<std::size_t>(n + 1)) {
      throw InputError("sphere fit: trimming outliers beyond " + std::to_string(threshold * 1e3) + " um left " +
                       std::to_string(trimmed->count) + " points; it takes at least " + PointsNeeded(fixed));
    }
    if (select.changed > 0) std::swap(fit.inlier, next);
    return select.changed;
  };

  NormalEquations normal;
  if (coarse && options.outliers != SphereOutliers::kNone) {
    trim(&normal);  // the coarse fit knows where the outliers are
  } else {
    normal = Accumulate(points, fit.inlier, origin, theta, options.residual);
  }
  bool last = false;
  for (int round = 0;; ++round) {
    const SolveResult solved = options.solver == SphereSolver::kCeres
                                   ? SolveCeres(points, fit.inlier, origin, theta, options)
                                   : SolveNormalEquations(points, fit.inlier, origin, theta, normal, scale, options);
    theta = solved.theta;
    normal = solved.normal;
    fit.iterations += solved.iterations;
    fit.converged = solved.converged;
    fit.stop_reason = solved.stop_reason;
    fit.trim_rounds = round;
    if (last || options.outliers == SphereOutliers::kNone || round >= options.max_trim_rounds) break;
    const std::size_t changed = trim(&normal);
    if (changed == 0) break;
    // Settled when (almost) no point changes side: a few points in 10 000 crossing the threshold move the fit
    // by a small fraction of its uncertainty; one more solve (usually without a pass: its first step is below
    // the tolerance) takes them into account, and chasing the next few is not worth a pass each.
    last = changed <= points.size() / 10000;
  }

  fit.centre_mm = origin + theta.head<3>();
  fit.radius_mm = theta.w();
  fit.inliers = normal.count;
  const double dof = static_cast<double>(normal.count) - n;
  const double variance = normal.cost / dof;
  fit.residual_sigma_mm = std::sqrt(variance);
  const Eigen::MatrixXd jtj = normal.jtj.topLeftCorner(n, n);
  const Eigen::MatrixXd covariance =
      variance * Decompose<Eigen::LDLT<Eigen::MatrixXd>>(jtj, "the sphere fit's covariance").solve(Eigen::MatrixXd::Identity(n, n));
  fit.centre_covariance_mm2 = covariance.topLeftCorner<3, 3>();
  fit.radius_sigma_mm = fixed ? 0.0 : std::sqrt(std::max(0.0, covariance(3, 3)));
  const double count = static_cast<double>(normal.count);
  fit.min_deviation_mm = normal.min_deviation;
  fit.max_deviation_mm = normal.max_deviation;
  fit.mean_deviation_mm = normal.sum_deviation / count;
  fit.rms_deviation_mm = std::sqrt(normal.sum_deviation2 / count);
  return fit;
}

Eigen::MatrixXd SphereCramerRaoBound(std::span<const Eigen::Vector3d> points, const Sphere& truth, double sigma_mm,
                                     SphereResidual residual, bool fixed_radius) {
  const int n = fixed_radius ? 3 : 4;
  Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
  for (const auto& p : points) {
    // At the truth the residual is zero, so only the derivative of the distance counts, not of the weight.
    const Eigen::Vector4d j = EvaluatePoint(p - truth.centre_mm, truth.radius_mm, residual).jacobian;
    jtj.selfadjointView<Eigen::Lower>().rankUpdate(j);
  }
  jtj = jtj.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd block = jtj.topLeftCorner(n, n);
  return sigma_mm * sigma_mm *
         Decompose<Eigen::LDLT<Eigen::MatrixXd>>(block, "the Cramer-Rao bound of a sphere").solve(Eigen::MatrixXd::Identity(n, n));
}

}  // namespace fvm::imaging
