#include "imaging/sphere_fit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

// Where the published 6 x 6 grid's calotte 1 lies on the stage ([Pérez 2019] Table 1, case a): coordinates of -150 mm
// test that the fit keeps its digits far from the origin.
const Eigen::Vector3d kCentre(-154.5487, -115.4767, -50.3624);
constexpr double kRadius = 0.25;  // the grid's calottes: 0.5 mm hemispherical holes ([Pérez 2019] 1.2)

// The lower half of the sphere sampled on a pixel grid, as a height map sees a calotte: points up to the largest
// slope the optics measure (75 degrees), heights exact.
std::vector<Eigen::Vector3d> CapPoints(const Eigen::Vector3d& centre, double radius, double pitch,
                                       double max_slope_deg = 75.0) {
  std::vector<Eigen::Vector3d> points;
  const double reach = radius * std::sin(max_slope_deg * M_PI / 180.0);
  const int n = static_cast<int>(std::ceil(reach / pitch));
  for (int iy = -n; iy <= n; ++iy) {
    for (int ix = -n; ix <= n; ++ix) {
      // Grid not centred on the calotte: a real map never is.
      const double x = (ix + 0.31) * pitch, y = (iy - 0.17) * pitch;
      if (x * x + y * y > reach * reach) continue;
      points.emplace_back(centre.x() + x, centre.y() + y, centre.z() - std::sqrt(radius * radius - x * x - y * y));
    }
  }
  return points;
}

std::vector<Eigen::Vector3d> WithHeightNoise(std::vector<Eigen::Vector3d> points, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (auto& p : points) p.z() += noise(rng);
  return points;
}

TEST(SphereFit, AlgebraicFitIsExactOnASphere) {
  const Sphere s = FitSphereAlgebraic(CapPoints(kCentre, kRadius, 0.01));
  EXPECT_LT((s.centre_mm - kCentre).norm(), 1e-9);
  EXPECT_NEAR(s.radius_mm, kRadius, 1e-9);
}

// Target of issue 4: a noise-free cap gives the centre to better than 1 nm, whichever residual, solver or radius.
TEST(SphereFit, NoiseFreeCapCentreWithinOneNanometre) {
  const std::vector<Eigen::Vector3d> points = CapPoints(kCentre, kRadius, 0.005);
  for (const SphereResidual residual : {SphereResidual::kOrthogonal, SphereResidual::kHeight}) {
    for (const SphereSolver solver : {SphereSolver::kNormalEquations, SphereSolver::kCeres}) {
      for (const double fixed : {0.0, kRadius}) {
        SphereFitOptions options;
        options.residual = residual;
        options.solver = solver;
        options.fixed_radius_mm = fixed;
        const SphereFit fit = FitSphere(points, options);
        SCOPED_TRACE(testing::Message() << "residual " << static_cast<int>(residual) << " solver "
                                        << static_cast<int>(solver) << " fixed radius " << fixed);
        EXPECT_LT((fit.centre_mm - kCentre).norm(), 1e-6);
        EXPECT_NEAR(fit.radius_mm, kRadius, 1e-6);
        EXPECT_TRUE(fit.converged);
        EXPECT_EQ(fit.inliers, points.size()) << "trimming must keep every point of noise-free data";
        EXPECT_LT(fit.rms_deviation_mm, 1e-9);
      }
    }
  }
}

// A shallow cap (20 degrees of slope: a ball-nose calotte seen by a low-magnification lens) is the hard case
// for the algebraic start; the geometric fit must still land on the truth.
TEST(SphereFit, ShallowCapConvergesFromTheAlgebraicStart) {
  const std::vector<Eigen::Vector3d> points = WithHeightNoise(CapPoints(kCentre, 1.0, 0.01, 20.0), 2e-4, 3);
  const SphereFit fit = FitSphere(points);
  const Eigen::MatrixXd crb =
      SphereCramerRaoBound(CapPoints(kCentre, 1.0, 0.01, 20.0), {kCentre, 1.0}, 2e-4, SphereResidual::kOrthogonal);
  EXPECT_TRUE(fit.converged);
  for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(fit.centre_mm[k] - kCentre[k]), 4 * std::sqrt(crb(k, k)));
}

// A fit that runs out of iterations must say so, not report the last iterate as the minimum: on a shallow noisy
// cap the algebraic start is biased, one iteration (a damped first step) does not reach the converged centre to
// the 1e-3 sd the criterion asks, and the status says why it stopped.
TEST(SphereFit, ReportsNonConvergenceAsSuch) {
  const std::vector<Eigen::Vector3d> points = WithHeightNoise(CapPoints(kCentre, 1.0, 0.01, 20.0), 2e-4, 3);
  for (const SphereSolver solver : {SphereSolver::kNormalEquations, SphereSolver::kCeres}) {
    SphereFitOptions options;
    options.solver = solver;
    options.outliers = SphereOutliers::kNone;
    options.max_iterations = 1;
    const SphereFit stopped = FitSphere(points, options);
    EXPECT_FALSE(stopped.converged) << static_cast<int>(solver);
    EXPECT_THAT(stopped.stop_reason, ::testing::Not(::testing::HasSubstr("at the minimum"))) << static_cast<int>(solver);
    options.max_iterations = 100;
    const SphereFit done = FitSphere(points, options);
    EXPECT_TRUE(done.converged) << static_cast<int>(solver);
    EXPECT_THAT(done.stop_reason, ::testing::HasSubstr("at the minimum"));
    // The stopped fit is really elsewhere by the criterion's own measure: more than 1e-3 of the centre's
    // standard deviation from the converged centre (observed: 4e-3 sd for ours, 0.25 sd for Ceres).
    const double sd = std::sqrt(done.centre_covariance_mm2.trace());
    EXPECT_GT((stopped.centre_mm - done.centre_mm).norm(), 1e-3 * sd) << static_cast<int>(solver);
  }
}

// Target of issue 4: with Gaussian height noise the centre scatters over 100 seeds by no more than 1.2 x the
// Cramer-Rao bound sigma^2 (J^T J)^-1 at the truth. The height residual is the maximum-likelihood fit for
// noise in z, so it should reach the bound; with 100 seeds a sample standard deviation is known to 7 %, so
// 1.2 is a 2.8-sigma margin and 0.8 below catches a bound that is too loose.
TEST(SphereFit, HeightNoiseScatterWithinCramerRaoBound) {
  const double sigma = 1e-4;  // 0.1 um: the 10x lens' vertical resolution ([Pérez thesis] Table 5.2)
  const std::vector<Eigen::Vector3d> truth = CapPoints(kCentre, kRadius, 0.008);
  ASSERT_GT(truth.size(), 2500u);
  const Eigen::MatrixXd crb = SphereCramerRaoBound(truth, {kCentre, kRadius}, sigma, SphereResidual::kHeight);
  SphereFitOptions options;
  options.residual = SphereResidual::kHeight;
  constexpr int kSeeds = 100;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d reported = Eigen::Vector3d::Zero();
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const SphereFit fit = FitSphere(WithHeightNoise(truth, sigma, seed), options);
    const Eigen::Vector3d e = fit.centre_mm - kCentre;
    sum += e;
    sum2 += e.cwiseProduct(e);
    reported += fit.centre_covariance_mm2.diagonal().cwiseSqrt();
  }
  const Eigen::Vector3d mean = sum / kSeeds;
  const Eigen::Vector3d sd = ((sum2 - kSeeds * mean.cwiseProduct(mean)) / (kSeeds - 1)).cwiseSqrt();
  reported /= kSeeds;
  for (int k = 0; k < 3; ++k) {
    const double bound = std::sqrt(crb(k, k));
    SCOPED_TRACE(testing::Message() << "axis " << k << ": scatter " << sd[k] * 1e6 << " nm, bound " << bound * 1e6
                                    << " nm, reported " << reported[k] * 1e6 << " nm");
    EXPECT_LT(sd[k], 1.2 * bound);
    EXPECT_GT(sd[k], 0.8 * bound);
    EXPECT_LT(std::abs(mean[k]), 3 * bound / std::sqrt(kSeeds)) << "biased centre";
    // The reported covariance estimates sigma from ~3000 residuals (1.3 % precision): it must match the bound.
    EXPECT_NEAR(reported[k], bound, 0.05 * bound);
  }
}

// The orthogonal fit (what instrument software does) under the same height noise: unbiased, and how much it
// loses against the bound is a property of the geometry (steep flanks, where it weights heights by n_z^2).
TEST(SphereFit, OrthogonalFitUnderHeightNoiseIsUnbiasedAndNearTheBound) {
  const double sigma = 1e-4;
  const std::vector<Eigen::Vector3d> truth = CapPoints(kCentre, kRadius, 0.008);
  const Eigen::MatrixXd crb = SphereCramerRaoBound(truth, {kCentre, kRadius}, sigma, SphereResidual::kHeight);
  constexpr int kSeeds = 100;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const Eigen::Vector3d e = FitSphere(WithHeightNoise(truth, sigma, seed)).centre_mm - kCentre;
    sum += e;
    sum2 += e.cwiseProduct(e);
  }
  const Eigen::Vector3d mean = sum / kSeeds;
  const Eigen::Vector3d sd = ((sum2 - kSeeds * mean.cwiseProduct(mean)) / (kSeeds - 1)).cwiseSqrt();
  for (int k = 0; k < 3; ++k) {
    const double bound = std::sqrt(crb(k, k));
    SCOPED_TRACE(testing::Message() << "axis " << k << ": scatter " << sd[k] / bound << " x bound");
    EXPECT_LT(std::abs(mean[k]), 3 * sd[k] / std::sqrt(kSeeds));
    EXPECT_GT(sd[k], 0.8 * bound);
    EXPECT_LT(sd[k], 2.0 * bound);
  }
}

TEST(SphereFit, FixedRadiusUsesTheKnownBall) {
  const std::vector<Eigen::Vector3d> truth = CapPoints(kCentre, kRadius, 0.008);
  SphereFitOptions options;
  options.fixed_radius_mm = kRadius;
  options.residual = SphereResidual::kHeight;
  const SphereFit fit = FitSphere(WithHeightNoise(truth, 1e-4, 7), options);
  EXPECT_EQ(fit.radius_mm, kRadius);
  EXPECT_EQ(fit.radius_sigma_mm, 0.0);
  const Eigen::MatrixXd crb =
      SphereCramerRaoBound(truth, {kCentre, kRadius}, 1e-4, SphereResidual::kHeight, /*fixed_radius=*/true);
  for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(fit.centre_mm[k] - kCentre[k]), 4 * std::sqrt(crb(k, k)));
  // Knowing the radius removes its correlation with z: the centre's z is better determined than with it free.
  const Eigen::MatrixXd free = SphereCramerRaoBound(truth, {kCentre, kRadius}, 1e-4, SphereResidual::kHeight);
  EXPECT_LT(crb(2, 2), 0.5 * free(2, 2));
}

// The statistics the instrument reports: a checkerboard form error of +-1 um on the cap gives deviations of
// -1 and +1 um, a mean of 0 and an RMS of 1 um (the pattern is nearly orthogonal to what a sphere can absorb).
TEST(SphereFit, ReportsDeviationStatistics) {
  std::vector<Eigen::Vector3d> points = CapPoints(kCentre, kRadius, 0.005);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d u = (points[i] - kCentre).normalized();
    points[i] += (i % 2 ? 1e-3 : -1e-3) * u;
  }
  SphereFitOptions options;
  options.outliers = SphereOutliers::kNone;
  const SphereFit fit = FitSphere(points, options);
  EXPECT_NEAR(fit.min_deviation_mm, -1e-3, 2e-5);
  EXPECT_NEAR(fit.max_deviation_mm, 1e-3, 2e-5);
  EXPECT_NEAR(fit.mean_deviation_mm, 0.0, 2e-5);
  EXPECT_NEAR(fit.rms_deviation_mm, 1e-3, 1e-5);
  EXPECT_LT((fit.centre_mm - kCentre).norm(), 1e-5);
}

// Spikes (5 % of the points up to +-20 um off, as focus variation produces on steep flanks) are trimmed: the
// centre comes back to within 4 bounds of the truth; the plain least-squares fit is thrown off by far more.
TEST(SphereFit, TrimsSpikes) {
  const double sigma = 1e-4;
  const std::vector<Eigen::Vector3d> truth = CapPoints(kCentre, kRadius, 0.008);
  std::vector<Eigen::Vector3d> points = WithHeightNoise(truth, sigma, 11);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::size_t spikes = 0;
  for (auto& p : points) {
    if (uniform(rng) < 0.05) p.z() += 0.02 * (2 * uniform(rng) - 1), ++spikes;
  }
  const Eigen::MatrixXd crb = SphereCramerRaoBound(truth, {kCentre, kRadius}, sigma, SphereResidual::kHeight);
  SphereFitOptions options;
  options.residual = SphereResidual::kHeight;
  const SphereFit trimmed = FitSphere(points, options);
  EXPECT_GE(trimmed.points - trimmed.inliers, spikes * 9 / 10);
  EXPECT_LE(trimmed.points - trimmed.inliers, spikes + 20);
  for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(trimmed.centre_mm[k] - kCentre[k]), 4 * std::sqrt(crb(k, k)));
  options.outliers = SphereOutliers::kNone;
  const SphereFit plain = FitSphere(points, options);
  EXPECT_GT((plain.centre_mm - kCentre).norm(), 10 * (trimmed.centre_mm - kCentre).norm());
}

// Forty per cent of the points are not on the calotte at all (a neighbouring face, debris): RANSAC finds the
// sphere where trimming from a least-squares start could not.
TEST(SphereFit, RansacSurvivesGrossOutliers) {
  std::vector<Eigen::Vector3d> points = WithHeightNoise(CapPoints(kCentre, kRadius, 0.008), 1e-4, 5);
  const std::size_t good = points.size();
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> box(-0.3, 0.3);
  for (std::size_t i = 0; i < good * 2 / 3; ++i)
    points.push_back(kCentre + Eigen::Vector3d(box(rng), box(rng), box(rng)));
  SphereFitOptions options;
  options.outliers = SphereOutliers::kRansac;
  options.inlier_threshold_mm = 5e-4;
  options.seed = 3;
  const SphereFit fit = FitSphere(points, options);
  EXPECT_LT((fit.centre_mm - kCentre).norm(), 2e-5);
  EXPECT_NEAR(static_cast<double>(fit.inliers), static_cast<double>(good), 0.02 * good);
  // The same seed gives the same fit.
  EXPECT_EQ(FitSphere(points, options).centre_mm, fit.centre_mm);
}

TEST(SphereFit, SolversAgreeUnderNoise) {
  const std::vector<Eigen::Vector3d> points = WithHeightNoise(CapPoints(kCentre, kRadius, 0.008), 1e-4, 21);
  for (const SphereResidual residual : {SphereResidual::kOrthogonal, SphereResidual::kHeight}) {
    SphereFitOptions options;
    options.residual = residual;
    options.outliers = SphereOutliers::kNone;
    const SphereFit ours = FitSphere(points, options);
    options.solver = SphereSolver::kCeres;
    const SphereFit ceres = FitSphere(points, options);
    // Both stop within 1e-3 standard deviations of the minimum (5 pm here).
    EXPECT_LT((ours.centre_mm - ceres.centre_mm).norm(), 1e-8);
    EXPECT_NEAR(ours.radius_mm, ceres.radius_mm, 1e-8);
  }
}

TEST(SphereFit, TooFewPointsIsAClearError) {
  const std::vector<Eigen::Vector3d> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  try {
    FitSphere(three);
    FAIL() << "no error for 3 points";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("3 points are too few"));
    EXPECT_THAT(e.what(), testing::HasSubstr("at least 5"));
  }
  SphereFitOptions fixed;
  fixed.fixed_radius_mm = 1.0;
  EXPECT_THROW(FitSphere(three, fixed), InputError);
  EXPECT_THROW(FitSphereAlgebraic(three), InputError);
}

TEST(SphereFit, DegeneratePointsAreAClearError) {
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i < 100; ++i) plane.emplace_back(i % 10, i / 10, 0.0);
  try {
    FitSphere(plane);
    FAIL() << "no error for points on a plane";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("plane"));
  }
  std::vector<Eigen::Vector3d> with_nan = CapPoints(kCentre, kRadius, 0.02);
  with_nan[3].z() = NAN;
  EXPECT_THROW(FitSphere(with_nan), InputError);
  SphereFitOptions bad;
  bad.outliers = SphereOutliers::kRansac;  // without a threshold
  EXPECT_THROW(FitSphere(CapPoints(kCentre, kRadius, 0.02), bad), std::invalid_argument);
}

}  // namespace
}  // namespace fvm::imaging
