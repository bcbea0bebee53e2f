// Sphere and plane fits to point sets with a recorded truth (fixed seeds): caps of a few degrees to whole
// spheres, the exactly determined cases, stray points, and every kind of bad input the issue names. The certified
// NIST sets are in realdata_test.cc.

#include "imaging/shape_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/input_error.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {
namespace {

const Eigen::Vector3d kCentre(412.345, -87.654, 231.5);  // far from the origin: the fit must keep its digits

// Points spread evenly (a Fibonacci lattice) over the cap of half-angle cap_deg around direction +z, each moved
// along its normal by Gaussian noise of sigma_mm.
std::vector<Eigen::Vector3d> SpherePoints(double radius, double cap_deg, int n, double sigma_mm, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  std::vector<Eigen::Vector3d> points;
  const double min_cos = std::cos(cap_deg * M_PI / 180.0);
  for (int i = 0; i < n; ++i) {
    const double cos_t = 1.0 - (1.0 - min_cos) * (i + 0.5) / n;
    const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
    const double phi = i * M_PI * (3.0 - std::sqrt(5.0));
    const Eigen::Vector3d u(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
    points.push_back(kCentre + (radius + (sigma_mm > 0 ? noise(rng) : 0.0)) * u);
  }
  return points;
}

class SphereCaps : public ::testing::TestWithParam<double> {};

// The fit's error against the truth, per coordinate, stays within 4 of the standard uncertainties it reports,
// and those agree with the Cramer-Rao bound of the points (sigma^2 (J^T J)^-1 at the truth) within 15 %: the
// residual variance over 400 points estimates sigma to about 4 %.
TEST_P(SphereCaps, CentreAndRadiusWithinTheirUncertainty) {
  const double cap_deg = GetParam(), radius = 12.5, sigma = 0.002;
  const std::vector<Eigen::Vector3d> points = SpherePoints(radius, cap_deg, 400, sigma, 7);
  const ShapeFit fit = FitShape(points);
  ASSERT_TRUE(fit.has_uncertainty);
  EXPECT_EQ(fit.outliers, 0u);
  EXPECT_NEAR(fit.rms_mm, sigma, 0.15 * sigma);
  const Eigen::MatrixXd bound = SphereCramerRaoBound(points, Sphere{kCentre, radius}, sigma, SphereResidual::kOrthogonal);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(fit.centre_mm[k], kCentre[k], 4 * fit.u_centre_mm[k]) << "axis " << k;
    EXPECT_NEAR(fit.u_centre_mm[k], std::sqrt(bound(k, k)), 0.15 * std::sqrt(bound(k, k))) << "axis " << k;
  }
  EXPECT_NEAR(fit.radius_mm, radius, 4 * fit.u_radius_mm);
  EXPECT_NEAR(fit.u_radius_mm, std::sqrt(bound(3, 3)), 0.15 * std::sqrt(bound(3, 3)));
}

INSTANTIATE_TEST_SUITE_P(FewDegreesToWhole, SphereCaps, ::testing::Values(3.0, 10.0, 45.0, 90.0, 180.0));

// Noise-free points give the sphere to rounding, from a 3-degree cap (where the algebraic start alone is off)
// to the whole sphere.
TEST(ShapeFit, ExactPointsGiveTheSphereToRounding) {
  for (const double cap : {3.0, 180.0}) {
    const ShapeFit fit = FitShape(SpherePoints(12.5, cap, 50, 0.0, 1));
    EXPECT_LT((fit.centre_mm - kCentre).norm(), 1e-9) << cap << " deg";
    EXPECT_NEAR(fit.radius_mm, 12.5, 1e-9) << cap << " deg";
  }
}

TEST(ShapeFit, FourPointsGiveTheSphereThroughThemWithoutUncertainty) {
  const std::vector<Eigen::Vector3d> points = {kCentre + Eigen::Vector3d(3, 0, 0), kCentre + Eigen::Vector3d(0, 3, 0),
                                               kCentre + Eigen::Vector3d(0, 0, 3), kCentre + Eigen::Vector3d(-3, 0, 0)};
  const ShapeFit fit = FitShape(points);
  EXPECT_LT((fit.centre_mm - kCentre).norm(), 1e-12);
  EXPECT_NEAR(fit.radius_mm, 3.0, 1e-12);
  EXPECT_FALSE(fit.has_uncertainty);
  EXPECT_LT(fit.rms_mm, 1e-12);
}

// A plane through kCentre tilted 30 degrees about x then 20 about z, sampled on a 40 x 30 mm grid with noise.
struct PlaneCase {
  Eigen::Vector3d normal;
  std::vector<Eigen::Vector3d> points;
};

PlaneCase PlanePoints(double sigma_mm, std::uint64_t seed) {
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(20 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(30 * M_PI / 180, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  PlaneCase c;
  c.normal = turn.col(2);
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 0; ix < 30; ++ix) {
      const Eigen::Vector3d local(ix * 40.0 / 29 - 20, iy * 30.0 / 19 - 15, sigma_mm > 0 ? noise(rng) : 0.0);
      c.points.push_back(kCentre + turn * local);
    }
  }
  return c;
}

// Angle between two lines (the normal's sign is free).
double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), std::abs(a.dot(b)));
}

TEST(ShapeFit, PlaneNormalWithinItsUncertainty) {
  const double sigma = 0.003;
  const PlaneCase c = PlanePoints(sigma, 3);
  ShapeFitOptions options;
  options.shape = Shape::kPlane;
  const ShapeFit fit = FitShape(c.points, options);
  // The tilt about the grid's long axis is the worse one: its variance is sigma^2 / sum(y^2) over the 600 points.
  double sum_y2 = 0;
  for (int iy = 0; iy < 20; ++iy) sum_y2 += 30 * std::pow(iy * 30.0 / 19 - 15, 2);
  const double expected_u = sigma / std::sqrt(sum_y2);
  EXPECT_NEAR(fit.u_normal_rad, expected_u, 0.1 * expected_u);
  EXPECT_LT(Angle(fit.normal, c.normal), 4 * std::sqrt(2.0) * fit.u_normal_rad);
  EXPECT_NEAR(fit.normal.norm(), 1.0, 1e-15);
  // The centroid of the points, computed here directly.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : c.points) mean += p;
  mean /= static_cast<double>(c.points.size());
  EXPECT_LT((fit.point_mm - mean).norm(), 1e-11);
  EXPECT_NEAR(fit.rms_mm, sigma, 0.1 * sigma);
}

TEST(ShapeFit, ThreePointsGiveThePlaneThroughThem) {
  const std::vector<Eigen::Vector3d> points = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  ShapeFitOptions options;
  options.shape = Shape::kPlane;
  const ShapeFit fit = FitShape(points, options);
  EXPECT_LT(Angle(fit.normal, Eigen::Vector3d::UnitZ()), 1e-15);
  EXPECT_GT(fit.normal.z(), 0);  // the largest component positive
  EXPECT_FALSE(fit.has_uncertainty);
}

// A 30-degree cap of a 50 mm sphere (60 %) among a background wall and scattered points (40 %): the robust fit
// keeps the sphere's points, leaves out every point farther than 1 mm from it, and the result is the plain fit to
// the points it kept.
TEST(ShapeFit, RobustFindsTheSphereAmongStrayPoints) {
  const double radius = 50, sigma = 0.05;
  std::vector<Eigen::Vector3d> points = SpherePoints(radius, 60, 1500, sigma, 11);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::size_t far = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p = i < 700 ? kCentre + Eigen::Vector3d(120 * u(rng), 120 * u(rng), -30 + 0.05 * u(rng))
                                      : kCentre + Eigen::Vector3d(100 * u(rng), 100 * u(rng), 100 * u(rng));
    far += std::abs((p - kCentre).norm() - radius) > 1.0;
    points.push_back(p);
  }
  ShapeFitOptions options;
  options.robust = true;
  const ShapeFit fit = FitShape(points, options);
  EXPECT_NEAR(fit.radius_mm, radius, 4 * fit.u_radius_mm);
  EXPECT_LT((fit.centre_mm - kCentre).norm(), 0.05);
  EXPECT_GE(fit.outliers, far);
  EXPECT_LE(fit.outliers, far + 30);  // 3 sigma trimming of 1500 good points loses about 4 of them
  std::size_t kept_far = 0;
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!fit.inlier[i]) continue;
    kept.push_back(points[i]);
    kept_far += std::abs((points[i] - kCentre).norm() - radius) > 1.0;
  }
  EXPECT_EQ(kept_far, 0u);
  const ShapeFit plain = FitShape(kept);
  EXPECT_LT((plain.centre_mm - fit.centre_mm).norm(), 1e-9);
  EXPECT_NEAR(plain.radius_mm, fit.radius_mm, 1e-9);
}

TEST(ShapeFit, RobustPlaneLeavesOutTheStrayPoints) {
  PlaneCase c = PlanePoints(0.003, 4);
  const std::size_t good = c.points.size();
  for (int i = 0; i < 200; ++i) c.points.push_back(kCentre + c.normal * (1.0 + 0.05 * i));
  ShapeFitOptions options;
  options.shape = Shape::kPlane;
  options.robust = true;
  const ShapeFit fit = FitShape(c.points, options);
  EXPECT_GE(fit.outliers, 200u);
  EXPECT_LE(fit.outliers, 210u);
  const ShapeFit plain = FitShape(std::span(c.points).first(good), ShapeFitOptions{Shape::kPlane});
  EXPECT_LT(Angle(fit.normal, c.normal), 4 * std::sqrt(2.0) * plain.u_normal_rad);
}

void ExpectInputError(const std::vector<Eigen::Vector3d>& points, Shape shape, const std::string& reason) {
  ShapeFitOptions options;
  options.shape = shape;
  try {
    FitShape(points, options);
    ADD_FAILURE() << "no error; expected one saying '" << reason << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

TEST(ShapeFit, BadInputIsNamed) {
  const std::vector<Eigen::Vector3d> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  ExpectInputError(three, Shape::kSphere, "3 points cannot determine a sphere; it takes at least 4");
  ExpectInputError({{0, 0, 0}, {1, 0, 0}}, Shape::kPlane, "2 points cannot determine a plane; it takes at least 3");
  // Coplanar points (a plane's grid) determine no sphere.
  ExpectInputError(PlanePoints(0.0, 1).points, Shape::kSphere, "lie on a plane or a line");
  ExpectInputError({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}}, Shape::kPlane, "lie on a line");
  ExpectInputError({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}, Shape::kPlane, "all points coincide");
  std::vector<Eigen::Vector3d> with_nan = SpherePoints(5, 90, 20, 0.0, 1);
  with_nan[6].y() = std::numeric_limits<double>::quiet_NaN();
  ExpectInputError(with_nan, Shape::kSphere, "point 7 of 20 has a NaN or infinite coordinate");
  with_nan[6].y() = std::numeric_limits<double>::infinity();
  ExpectInputError(with_nan, Shape::kPlane, "point 7 of 20 has a NaN or infinite coordinate");
  // A 50 mm ball read as micrometres taken for metres: radius 50 m.
  std::vector<Eigen::Vector3d> huge = SpherePoints(50e3, 20, 30, 0.0, 1);
  ExpectInputError(huge, Shape::kSphere, " m, is above 10 m: the points are nearly coplanar or their unit is wrong");
}

}  // namespace
}  // namespace fvm::imaging
