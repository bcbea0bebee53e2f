// Real and certified data that no one on this project made (../shared/realdata, see its README): NIST's
// Algorithm Testing System reference sets for spheres and planes against their certified fits, and NIST's
// terrestrial laser scans of a 100 mm sphere among stray points. Skipped where ../shared is absent (a user's clone).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <iostream>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/shape_fit.h"

namespace fvm::imaging {
namespace {

const std::filesystem::path kRealData = FVM_REALDATA_DIR;

#define SKIP_WITHOUT_REALDATA(path)                                                         \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path.string() << " is absent (no ../shared)"

// A .fit file: the certified numbers, one per line.
std::vector<double> ReadNumbers(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), std::abs(a.dot(b)));
}

// NIST ATS L2 spheres: centre and diameter within 1e-8 mm of the certified orthogonal-distance fit, on every
// set (4 to 457 points, caps of 45 degrees to more than hemispheres, radii 1 to 250 mm, 1000 mm from the origin).
TEST(NistSpheres, EqualTheCertifiedFit) {
  const std::filesystem::path dir = kRealData / "spheres/nist-l2";
  SKIP_WITHOUT_REALDATA(dir);
  int sets = 0;
  double worst_centre = 0, worst_diameter = 0;
  for (int n = 1; n <= 15; ++n) {
    const std::filesystem::path ds = dir / ("sph" + std::to_string(n) + ".ds");
    if (!std::filesystem::exists(ds)) continue;
    const std::vector<double> certified = ReadNumbers(dir / ("sph" + std::to_string(n) + ".fit"));
    ASSERT_EQ(certified.size(), 4u) << ds;
    const ShapeFit fit = FitShape(ReadPointCloud(ds, PointCloudFormat::kXyz).points);
    const double centre = (fit.centre_mm - Eigen::Vector3d(certified[0], certified[1], certified[2])).cwiseAbs().maxCoeff();
    const double diameter = std::abs(2 * fit.radius_mm - certified[3]);
    EXPECT_LT(centre, 1e-8) << ds;
    EXPECT_LT(diameter, 1e-8) << ds;
    worst_centre = std::max(worst_centre, centre), worst_diameter = std::max(worst_diameter, diameter);
    ++sets;
  }
  EXPECT_EQ(sets, 15);
  RecordProperty("worst_centre_mm", std::to_string(worst_centre));
  RecordProperty("worst_diameter_mm", std::to_string(worst_diameter));
  std::cout << "NIST spheres: " << sets << " sets, worst centre " << worst_centre << " mm, worst diameter "
            << worst_diameter << " mm\n";
}

// NIST ATS L2 planes: the centroid within 1e-8 mm, the normal within 1e-9 rad (sign free).
TEST(NistPlanes, EqualTheCertifiedFit) {
  const std::filesystem::path dir = kRealData / "planes/nist-l2";
  SKIP_WITHOUT_REALDATA(dir);
  int sets = 0;
  double worst_point = 0, worst_angle = 0;
  ShapeFitOptions options;
  options.shape = Shape::kPlane;
  for (int n = 1; n <= 15; ++n) {
    const std::filesystem::path ds = dir / ("pla" + std::to_string(n) + ".ds");
    if (!std::filesystem::exists(ds)) continue;
    const std::vector<double> certified = ReadNumbers(dir / ("pla" + std::to_string(n) + ".fit"));
    ASSERT_EQ(certified.size(), 6u) << ds;
    const ShapeFit fit = FitShape(ReadPointCloud(ds, PointCloudFormat::kXyz).points, options);
    const double point = (fit.point_mm - Eigen::Vector3d(certified[0], certified[1], certified[2])).cwiseAbs().maxCoeff();
    const double angle = Angle(fit.normal, Eigen::Vector3d(certified[3], certified[4], certified[5]));
    EXPECT_LT(point, 1e-8) << ds;
    EXPECT_LT(angle, 1e-9) << ds;
    worst_point = std::max(worst_point, point), worst_angle = std::max(worst_angle, angle);
    ++sets;
  }
  EXPECT_EQ(sets, 15);
  std::cout << "NIST planes: " << sets << " sets, worst point " << worst_point << " mm, worst normal " << worst_angle
            << " rad\n";
}

// The .ds count line is checked, not just skipped: a file cut short says so.
TEST(NistSpheres, CountLineIsChecked) {
  const std::filesystem::path ds = kRealData / "spheres/nist-l2/sph2.ds";
  SKIP_WITHOUT_REALDATA(ds);
  std::ifstream in(ds);
  std::stringstream text;
  text << in.rdbuf();
  std::string cut = text.str();
  cut = cut.substr(0, cut.rfind('\n', cut.size() - 2) + 1);  // drop the last point
  EXPECT_THROW(ParseXyz(cut, "sph2.ds"), InputError);
  EXPECT_EQ(ParseXyz(text.str(), "sph2.ds").points.size(), 9u);
}

class NistLaserScans : public ::testing::TestWithParam<int> {};

// Real scans of a 100 mm sphere among mixed pixels, mount and background (a plain fit gives 66-70 mm): the robust
// fit gives 50 mm within 0.3 mm, counts what it left out, and equals the plain fit of the points it kept (0.3 mm).
TEST_P(NistLaserScans, RobustFitFindsTheSphere) {
  const std::filesystem::path xyz = kRealData / ("spheres/nist-tls/SPH" + std::to_string(GetParam()) + ".xyz");
  SKIP_WITHOUT_REALDATA(xyz);
  PointCloudReadOptions metres;
  metres.mm_per_unit = 1000.0;
  const std::vector<Eigen::Vector3d> points = ReadPointCloud(xyz, PointCloudFormat::kXyz, metres).points;
  const ShapeFit plain_all = FitShape(points);
  EXPECT_GT(std::abs(plain_all.radius_mm - 50.0), 10.0) << "the stray points no longer spoil a plain fit";
  ShapeFitOptions options;
  options.robust = true;
  const ShapeFit fit = FitShape(points, options);
  EXPECT_NEAR(fit.radius_mm, 50.0, 0.3) << xyz;
  EXPECT_GT(fit.outliers, points.size() / 10) << xyz;
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (fit.inlier[i]) kept.push_back(points[i]);
  }
  ASSERT_EQ(kept.size() + fit.outliers, points.size());
  const ShapeFit plain = FitShape(kept);
  EXPECT_LT((plain.centre_mm - fit.centre_mm).norm(), 0.3) << xyz;
  std::cout << xyz.filename().string() << ": radius " << fit.radius_mm << " mm, " << fit.outliers << " of "
            << points.size() << " points left out, rms " << fit.rms_mm * 1e3 << " um\n";
}

INSTANTIATE_TEST_SUITE_P(Sph101To105, NistLaserScans, ::testing::Values(101, 102, 103, 104, 105));

}  // namespace
}  // namespace fvm::imaging
