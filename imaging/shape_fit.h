#pragma once
// A sphere or a plane fitted to any point set (a CMM probing of a reference sphere, a tracker nest, a cap or a
// flat measured as a few dozen points, a laser scan): the orthogonal-distance least-squares (Gaussian) element
// of ISO 10360-6 and the NIST Algorithm Testing System, with standard uncertainties from the residuals.
//
// Sphere: the algebraic start and Levenberg-Marquardt of sphere_fit.h, then Gauss-Newton in long double on the
// centred points until the step stops shrinking, so that the result is the minimum to the last digits of double
// (NIST certifies its reference fits to about 1e-13 relative). Plane: the centroid and the eigenvector of the
// smallest eigenvalue of the centred scatter matrix, formed and solved in long double (the right singular
// vector of the centred points, which is the orthogonal-distance plane in closed form).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace fvm::imaging {

enum class Shape { kSphere, kPlane };

// "sphere", "plane".
std::string ShapeName(Shape shape);

struct ShapeFitOptions {
  Shape shape = Shape::kSphere;
  // Find the shape among stray points (mixed pixels, the mount, background): a least-median-of-squares
  // consensus over shapes through 4 (sphere) or 3 (plane) points with a fixed seed, then orthogonal-distance
  // refits that drop the points beyond outlier_sigmas robust standard deviations (1.4826 x the median absolute
  // residual of the kept points) until the kept set is stable. Without it every point counts.
  bool robust = false;
  double outlier_sigmas = 3.0;
  std::uint64_t seed = 1;
  // A sphere larger than this is refused as absurd (a wrong unit); mm.
  double max_radius_mm = 1e4;
  void Check() const;  // throws std::invalid_argument
};

struct ShapeFit {
  Shape shape = Shape::kSphere;
  std::size_t points = 0;    // given
  std::size_t outliers = 0;  // left out by the robust search (0 without it)
  std::vector<bool> inlier;  // per given point
  double rms_mm = 0.0;       // RMS orthogonal distance of the kept points from the shape
  // Standard uncertainties need a residual: none when the points only just determine the shape (4 for a sphere,
  // 3 for a plane), where the shape passes through every point.
  bool has_uncertainty = false;

  // Sphere.
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0.0;
  Eigen::Vector3d u_centre_mm = Eigen::Vector3d::Zero();
  double u_radius_mm = 0.0;

  // Plane: the centroid of the kept points and the unit normal (its sign: the component of largest magnitude
  // positive), and the standard uncertainty of the normal's direction about the in-plane axis it is least sure
  // of (the larger of the two principal tilts), in radians.
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double u_normal_rad = 0.0;

  std::string method;  // for people: how the points were used, and how outliers were decided
};

// Throws InputError (without a file name: the caller adds it) for fewer points than the shape needs, NaN or
// infinite coordinates, points that do not determine the shape (coincident or collinear for a plane, coplanar
// for a sphere), or a sphere above max_radius_mm.
ShapeFit FitShape(std::span<const Eigen::Vector3d> points, const ShapeFitOptions& options = {});

}  // namespace fvm::imaging
