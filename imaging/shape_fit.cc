#include "imaging/shape_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/dense_decomposition.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "core/statistics.h"
#include "imaging/sample_consensus.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {
namespace {

// Robust thresholds never go below 1 nm: noise-free points keep their points.
constexpr double kMinThresholdMm = 1e-6;
// Up to this many points the sphere is polished in long double to the last digit (NIST's sets have up to ~500).
constexpr std::size_t kPolishPoints = 100000;

using Real = long double;  // 64-bit mantissa on x86-64: the last digits of a double survive the sums
using Vector3r = Eigen::Matrix<Real, 3, 1>;
using Vector4r = Eigen::Matrix<Real, 4, 1>;
using Matrix3r = Eigen::Matrix<Real, 3, 3>;
using Matrix4r = Eigen::Matrix<Real, 4, 4>;

// How the robust search decided, for people (the JSON's "method" and the text output).
std::string RobustMethod(const std::string& hypotheses, const ShapeFitOptions& options) {
  return "robust: least median of squares over " + hypotheses + " (seed " + std::to_string(options.seed) +
         "), kept the points within 2.5 robust standard deviations of the best, then orthogonal-distance refits "
         "without the points beyond " + FormatShortest(options.outlier_sigmas) +
         " robust standard deviations (1.4826 x median absolute distance) until the kept set was stable";
}

std::size_t Count(const std::vector<bool>& mask) {
  return static_cast<std::size_t>(std::count(mask.begin(), mask.end(), true));
}

Vector3r MeanOf(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask) {
  Vector3r sum = Vector3r::Zero();
  std::size_t n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (mask[i]) sum += points[i].cast<Real>(), ++n;
  }
  return sum / static_cast<Real>(n);
}

// The orthogonal-distance normal equations of a sphere (centre relative to `mean`, radius) over the kept points.
struct SphereSums {
  Matrix4r jtj = Matrix4r::Zero();
  Vector4r jtr = Vector4r::Zero();
  Real cost = 0;
};

SphereSums SumSphere(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask, const Vector3r& mean,
                     const Vector4r& theta) {
  SphereSums s;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    const Vector3r q = points[i].cast<Real>() - mean - theta.head<3>();
    const Real d = std::sqrt(q.squaredNorm());
    const Real r = d - theta(3);
    Vector4r j;
    j << -q / d, -1;
    s.jtj.selfadjointView<Eigen::Lower>().rankUpdate(j);
    s.jtr += j * r;
    s.cost += r * r;
  }
  s.jtj = s.jtj.selfadjointView<Eigen::Lower>();
  return s;
}

// Gauss-Newton from a start next to the minimum (the Levenberg-Marquardt solution of FitSphere, or the sphere
// through exactly 4 points) until the step stops shrinking: in long double its last steps are below a double's
// resolution, so the result is the least-squares sphere to the last digit the double can hold.
struct PolishedSphere {
  Sphere sphere;
  SphereSums sums;  // at the result
  bool converged = false;
};

PolishedSphere PolishSphere(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask, const Sphere& start) {
  const Vector3r mean = MeanOf(points, mask);
  Vector4r theta;
  theta << start.centre_mm.cast<Real>() - mean, static_cast<Real>(start.radius_mm);
  SphereSums sums = SumSphere(points, mask, mean, theta);
  const Real scale = std::max<Real>(theta(3), 1e-300L);
  Real last_step = std::numeric_limits<Real>::infinity();
  PolishedSphere out;
  for (int it = 0; it < 100; ++it) {
    const Vector4r step = -Decompose<Eigen::LDLT<Matrix4r>>(sums.jtj, "the sphere polish: its normal equations").solve(sums.jtr);
    if (!step.allFinite()) break;
    const SphereSums next = SumSphere(points, mask, mean, theta + step);
    if (next.cost > sums.cost * (1 + 1e-12L) + 1e-30L) break;  // no longer downhill: rounding has the last word
    theta += step;
    sums = next;
    const Real size = step.norm();
    if (size <= 1e-17L * scale || !(size < last_step)) {
      out.converged = true;
      break;
    }
    last_step = size;
  }
  // A step that no longer lowers the cost, or stops shrinking, at the level of a double's rounding, is the
  // minimum too.
  if (!out.converged) {
    const Vector4r step = -Decompose<Eigen::LDLT<Matrix4r>>(sums.jtj, "the sphere polish: its normal equations").solve(sums.jtr);
    out.converged = step.allFinite() && step.norm() <= 1e-12L * scale;
  }
  out.sphere.centre_mm = (mean + theta.head<3>()).cast<double>();
  out.sphere.radius_mm = static_cast<double>(theta(3));
  out.sums = sums;
  return out;
}

void CheckRadius(const ShapeFit& fit, const ShapeFitOptions& options) {
  if (!(fit.radius_mm <= options.max_radius_mm) || !fit.centre_mm.allFinite()) {
    throw InputError("the fitted sphere's radius, " + FormatShortest(fit.radius_mm * 1e-3) + " m, is above " +
                     FormatShortest(options.max_radius_mm * 1e-3) +
                     " m: the points are nearly coplanar or their unit is wrong (--unit)");
  }
}

ShapeFit FitSphereShape(std::span<const Eigen::Vector3d> points, const ShapeFitOptions& options) {
  ShapeFit fit;
  fit.inlier.assign(points.size(), true);
  Sphere start;
  std::optional<SphereFit> lm;
  if (points.size() == 4) {
    // Exactly determined: the sphere through the 4 points (or none, when they are coplanar).
    start = FitSphereAlgebraic(points);
    fit.method = "the sphere through the 4 points (no residual is left to estimate an uncertainty from)";
  } else {
    SphereFitOptions sphere;
    sphere.residual = SphereResidual::kOrthogonal;
    sphere.outliers = options.robust ? SphereOutliers::kLeastMedian : SphereOutliers::kNone;
    sphere.outlier_sigmas = options.outlier_sigmas;
    sphere.min_threshold_mm = kMinThresholdMm;
    sphere.seed = options.seed;
    sphere.max_iterations = 200;
    sphere.max_trim_rounds = 50;
    lm = FitSphere(points, sphere);
    start = Sphere{lm->centre_mm, lm->radius_mm};
    fit.inlier = lm->inlier;
    fit.method = options.robust ? RobustMethod("4-point spheres", options)
                                : "orthogonal-distance least squares on every point";
  }
  if (lm && points.size() > kPolishPoints) {
    // Large sets: FitSphere's minimum (its Gauss-Newton step below 1e-3 of a standard deviation) is kept; a
    // long-double pass costs ~15 ms per million points, and digits below u / 1000 are noise anyway.
    if (!lm->converged) throw NotConvergedError("sphere fit: " + lm->stop_reason);
    fit.centre_mm = lm->centre_mm;
    fit.radius_mm = lm->radius_mm;
    CheckRadius(fit, options);
    fit.outliers = lm->points - lm->inliers;
    fit.rms_mm = lm->rms_deviation_mm;
    fit.has_uncertainty = true;
    fit.u_centre_mm = lm->centre_covariance_mm2.diagonal().cwiseMax(0.0).cwiseSqrt();
    fit.u_radius_mm = lm->radius_sigma_mm;
    return fit;
  }
  const PolishedSphere polished = PolishSphere(points, fit.inlier, start);
  if (!polished.converged) {
    throw NotConvergedError("sphere fit: Gauss-Newton did not settle at the least-squares minimum");
  }
  fit.centre_mm = polished.sphere.centre_mm;
  fit.radius_mm = polished.sphere.radius_mm;
  CheckRadius(fit, options);
  const std::size_t kept = Count(fit.inlier);
  fit.outliers = points.size() - kept;
  fit.rms_mm = static_cast<double>(std::sqrt(polished.sums.cost / static_cast<Real>(kept)));
  fit.has_uncertainty = kept > 4;
  if (fit.has_uncertainty) {
    const Eigen::Matrix4d jtj = polished.sums.jtj.cast<double>();
    const double variance = static_cast<double>(polished.sums.cost) / static_cast<double>(kept - 4);
    const Eigen::Matrix4d covariance =
        variance * Decompose<Eigen::LDLT<Eigen::Matrix4d>>(jtj, "the sphere fit's covariance").solve(Eigen::Matrix4d::Identity());
    fit.u_centre_mm = covariance.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt();
    fit.u_radius_mm = std::sqrt(std::max(0.0, covariance(3, 3)));
  }
  return fit;
}

// The plane of the kept points: the centroid and the scatter matrix's eigen decomposition, in long double.
struct PlaneSolution {
  Vector3r centroid;
  Eigen::Matrix<Real, 3, 1> eigenvalues;  // ascending: the first is the sum of squared distances
  Matrix3r eigenvectors;
};

PlaneSolution SolvePlane(std::span<const Eigen::Vector3d> points, const std::vector<bool>& mask) {
  PlaneSolution s;
  s.centroid = MeanOf(points, mask);
  Matrix3r scatter = Matrix3r::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    const Vector3r q = points[i].cast<Real>() - s.centroid;
    scatter.selfadjointView<Eigen::Lower>().rankUpdate(q);
  }
  scatter = scatter.selfadjointView<Eigen::Lower>();
  const auto eigen = Decompose<Eigen::SelfAdjointEigenSolver<Matrix3r>>(scatter, "the plane fit: the scatter of the points");
  s.eigenvalues = eigen.eigenvalues().cwiseMax(Real(0));
  s.eigenvectors = eigen.eigenvectors();
  return s;
}

// Least median of squares over planes through 3 points (as kLeastMedian does for spheres), scored on at most
// 2000 points; returns the points within 2.5 robust standard deviations of the best plane.
std::vector<bool> LeastMedianPlane(std::span<const Eigen::Vector3d> points, std::uint64_t seed) {
  struct Plane {
    Eigen::Vector3d point, normal;
  };
  const auto through = [](const std::array<Eigen::Vector3d, 3>& p) -> std::optional<Plane> {
    const Eigen::Vector3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
    if (!(cross.norm() > 0)) return std::nullopt;
    return Plane{p[0], cross.normalized()};
  };
  const auto distance = [](const Plane& plane, const Eigen::Vector3d& p) { return plane.normal.dot(p - plane.point); };
  const ConsensusSearch<Plane> search = SearchConsensus<3, Plane>(points, seed, 1000, std::nullopt, through, distance);
  std::vector<bool> inlier(points.size(), true);
  if (!search.best) return inlier;  // every triple collinear: the plane fit says so
  const double threshold = LeastMedianThreshold(search.score, search.scored_points, 3, kMinThresholdMm);
  for (std::size_t i = 0; i < points.size(); ++i) inlier[i] = std::abs(distance(*search.best, points[i])) <= threshold;
  return inlier;
}

ShapeFit FitPlaneShape(std::span<const Eigen::Vector3d> points, const ShapeFitOptions& options) {
  ShapeFit fit;
  fit.inlier.assign(points.size(), true);
  fit.method = "orthogonal-distance least squares on every point";
  if (options.robust && points.size() > 3) {
    fit.inlier = LeastMedianPlane(points, options.seed);
    fit.method = RobustMethod("3-point planes", options);
  }
  PlaneSolution plane;
  for (int round = 0; round < 50; ++round) {
    if (Count(fit.inlier) < 3) throw InputError("plane fit: fewer than 3 points agree with any plane");
    plane = SolvePlane(points, fit.inlier);
    if (!options.robust) break;
    const Vector3r normal = plane.eigenvectors.col(0);
    std::vector<double> distance(points.size()), kept;
    for (std::size_t i = 0; i < points.size(); ++i) {
      distance[i] = static_cast<double>(std::abs(normal.dot(points[i].cast<Real>() - plane.centroid)));
      if (fit.inlier[i]) kept.push_back(distance[i]);
    }
    const double threshold = std::max(options.outlier_sigmas * 1.4826 * HighMedian(std::move(kept)), kMinThresholdMm);
    std::vector<bool> next(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) next[i] = distance[i] <= threshold;
    if (next == fit.inlier || Count(next) < 3) break;
    fit.inlier = std::move(next);
  }
  const std::size_t kept = Count(fit.inlier);
  const Real largest = plane.eigenvalues(2);
  if (!(largest > 0)) throw InputError("plane fit: all points coincide; no plane passes through them");
  // Collinear: the points' spread across their line below 1e-9 of their spread along it (rounding leaves ~1e-16).
  if (!(plane.eigenvalues(1) > Real(1e-18) * largest)) {
    throw InputError("plane fit: the points lie on a line; they do not determine a plane");
  }
  Eigen::Vector3d normal = plane.eigenvectors.col(0).cast<double>().normalized();
  Eigen::Index largest_component;
  normal.cwiseAbs().maxCoeff(&largest_component);
  if (normal(largest_component) < 0) normal = -normal;
  fit.normal = normal;
  fit.point_mm = plane.centroid.cast<double>();
  fit.outliers = points.size() - kept;
  fit.rms_mm = static_cast<double>(std::sqrt(plane.eigenvalues(0) / static_cast<Real>(kept)));
  fit.has_uncertainty = kept > 3;
  if (fit.has_uncertainty) {
    // A tilt t about in-plane axis k moves a point at distance s_k along the other axis by t s_k: the tilt's
    // variance is sigma^2 / sum s_k^2 = sigma^2 / eigenvalue; the smaller in-plane eigenvalue is the worse tilt.
    const Real variance = plane.eigenvalues(0) / static_cast<Real>(kept - 3);
    fit.u_normal_rad = static_cast<double>(std::sqrt(variance / plane.eigenvalues(1)));
  }
  return fit;
}

}  // namespace

std::string ShapeName(Shape shape) { return shape == Shape::kSphere ? "sphere" : "plane"; }

void ShapeFitOptions::Check() const {
  if (!(outlier_sigmas > 0) || !std::isfinite(outlier_sigmas)) {
    throw std::invalid_argument("shape fit: outlier_sigmas must be positive");
  }
  if (!(max_radius_mm > 0)) throw std::invalid_argument("shape fit: max_radius_mm must be positive");
}

ShapeFit FitShape(std::span<const Eigen::Vector3d> points, const ShapeFitOptions& options) {
  options.Check();
  const std::size_t needed = options.shape == Shape::kSphere ? 4 : 3;
  if (points.size() < needed) {
    throw InputError(std::to_string(points.size()) + (points.size() == 1 ? " point" : " points") +
                     " cannot determine a " + ShapeName(options.shape) + "; it takes at least " +
                     std::to_string(needed));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("point " + std::to_string(i + 1) + " of " + std::to_string(points.size()) +
                       " has a NaN or infinite coordinate; leave invalid points out");
    }
  }
  ShapeFit fit = options.shape == Shape::kSphere ? FitSphereShape(points, options) : FitPlaneShape(points, options);
  fit.shape = options.shape;
  fit.points = points.size();
  return fit;
}

}  // namespace fvm::imaging
