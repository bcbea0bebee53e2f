#pragma once
// Least-squares sphere fits to measured surface points: the calotte centre that stage calibration consumes
// ([Pérez thesis] section 5.7.2: the instrument fits a sphere to the calotte's points and reports the centre, the
// radius and the min / max / mean deviation from the sphere).
//
// Pipeline: an algebraic start (linear least squares on |p|^2 = 2 c.p + k), optionally a seeded RANSAC
// consensus set, then the geometric fit (Levenberg-Marquardt on orthogonal distances), repeated with outliers
// trimmed until the inlier set is stable. The default solver sums the 4 x 4 normal equations in one pass over
// the points per iteration (a million points in tens of milliseconds); the Ceres solver (automatic derivatives,
// one residual block per point) solves the same problem and is kept as the reference the tests compare with.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace fvm::imaging {

struct Sphere {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0.0;
};

// What the residual of a point is; both are zero for a point on the sphere.
enum class SphereResidual {
  // The orthogonal distance |p - c| - r: maximum likelihood when the noise is isotropic or along the normal
  // (point clouds, tactile probing); what instrument software fits.
  kOrthogonal,
  // The orthogonal distance divided by |n_z| (n the sphere's normal at the point), which is the point's height
  // above the sphere to first order: maximum likelihood when the noise is in z only, as in a height map from
  // focus variation. On steep flanks it trusts the distance more than kOrthogonal does, because a height error
  // there moves the point mostly along the surface. |n_z| is floored at 0.1 (84 degrees).
  kHeight,
};

enum class SphereOutliers {
  kNone,    // every point counts
  kTrim,    // refit without the points beyond the threshold until the inlier set no longer changes
  kRansac,  // a consensus set first (needs inlier_threshold_mm), then kTrim
  // A consensus set with no threshold to give: the 4-point sphere with the least median squared residual
  // (Rousseeuw 1984: up to half the points may be anything), its inliers those within 2.5 robust standard
  // deviations of it (Rousseeuw and Leroy 1987), then kTrim. For point sets whose noise is not known.
  kLeastMedian,
};

enum class SphereSolver {
  kNormalEquations,  // Levenberg-Marquardt on J^T J summed in one pass; exact derivatives; the fast one
  kCeres,            // Ceres Levenberg-Marquardt, automatic derivatives, one residual block per point
};

struct SphereFitOptions {
  double fixed_radius_mm = 0.0;  // > 0: the radius is known (the ball that milled the calotte); 0: estimate it
  SphereResidual residual = SphereResidual::kOrthogonal;
  SphereOutliers outliers = SphereOutliers::kTrim;
  SphereSolver solver = SphereSolver::kNormalEquations;
  // Trimming threshold: outlier_sigmas robust standard deviations (1.4826 x the median absolute residual), but
  // never below min_threshold_mm, so that noise-free data keeps its points. A positive inlier_threshold_mm
  // replaces both (and is the RANSAC threshold).
  double outlier_sigmas = 3.5;
  double min_threshold_mm = 1e-5;
  double inlier_threshold_mm = 0.0;
  int max_trim_rounds = 10;
  int max_iterations = 100;  // Levenberg-Marquardt iterations per fit
  int ransac_iterations = 1000;
  std::uint64_t seed = 1;  // RANSAC's draws
  void Check() const;      // throws std::invalid_argument
};

struct SphereFit {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0.0;
  // sigma^2 (J^T J)^-1 at the solution, sigma^2 the residual variance of the inliers (in the units of the chosen
  // residual: with kHeight it estimates the height noise). The centre block, and the radius' standard deviation
  // (0 when the radius was fixed).
  Eigen::Matrix3d centre_covariance_mm2 = Eigen::Matrix3d::Zero();
  double radius_sigma_mm = 0.0;
  double residual_sigma_mm = 0.0;  // sigma above
  // What the instrument reports: orthogonal deviations |p - c| - r of the inliers (positive away from the
  // centre), their min, max, mean and RMS.
  double min_deviation_mm = 0.0;
  double max_deviation_mm = 0.0;
  double mean_deviation_mm = 0.0;
  double rms_deviation_mm = 0.0;
  std::size_t points = 0;
  std::size_t inliers = 0;
  std::vector<bool> inlier;  // per input point
  int iterations = 0;        // Levenberg-Marquardt iterations over all trimming rounds
  int trim_rounds = 0;
  // Whether the last fit reached the minimum (the Gauss-Newton step below 1e-3 of each parameter's standard
  // deviation, or Ceres' convergence): false when it ran out of iterations or no step lowered the cost while the
  // step to the minimum was still large. The centre is then the last iterate, not a least-squares solution.
  bool converged = false;
  std::string stop_reason;  // for people: "at the minimum", "iteration limit (100) reached", "stuck: ..."
};

// The sphere minimising sum (|p|^2 - 2 c.p - k)^2 (k = r^2 - |c|^2), in coordinates centred on the points'
// mean. Exact for points on a sphere, biased under noise (a start, not a result). Throws InputError for fewer
// than 4 points or points on a plane or a line.
Sphere FitSphereAlgebraic(std::span<const Eigen::Vector3d> points);

// The geometric fit. Throws InputError when there are too few points (5, or 4 with a fixed radius: one more than
// the unknowns, so that a residual is left to estimate the noise from), the points do not determine a sphere,
// or trimming leaves too few; std::invalid_argument for inconsistent options.
SphereFit FitSphere(std::span<const Eigen::Vector3d> points, const SphereFitOptions& options = {});

// The Cramer-Rao bound of the centre (and radius) for points on a known sphere under Gaussian noise of standard
// deviation sigma_mm in the chosen residual's direction (kOrthogonal: along the normal; kHeight: along z):
// sigma^2 (J^T J)^-1 of the residuals at the truth, 4 x 4 (centre, radius) or 3 x 3 with a fixed radius.
Eigen::MatrixXd SphereCramerRaoBound(std::span<const Eigen::Vector3d> points, const Sphere& truth, double sigma_mm,
                                     SphereResidual residual, bool fixed_radius = false);

}  // namespace fvm::imaging
