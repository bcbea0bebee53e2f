#include "artefacts/simulation/calotte_surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace fvm::artefacts {
namespace {

double X(const imaging::HeightMap& map, int ix) { return map.x0_mm + ix * map.dx_mm; }
double Y(const imaging::HeightMap& map, int iy) { return map.y0_mm + iy * map.dy_mm; }

TEST(CalotteSurface, HemisphereHeightsAreExact) {
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.005;
  o.offset_mm = Eigen::Vector2d(3.0, -2.0);
  o.z0_mm = 0.5;
  const CalotteSurface s = RenderCalotteSurface(SingleCalotte(0.25), o);
  ASSERT_EQ(s.truth.size(), 1u);
  const Eigen::Vector3d c = s.truth[0].centre;
  EXPECT_EQ(c, Eigen::Vector3d(3.0, -2.0, 0.5));  // a hemisphere: the centre lies in the face
  // The map spans the calotte plus the margin on every side.
  EXPECT_LE(X(s.map, 0), 3.0 - 1.25);
  EXPECT_GE(X(s.map, s.map.size_x - 1), 3.0 + 1.2);
  int checked = 0, steep = 0;
  for (int iy = 0; iy < s.map.size_y; ++iy) {
    for (int ix = 0; ix < s.map.size_x; ++ix) {
      const double x = X(s.map, ix) - c.x(), y = Y(s.map, iy) - c.y(), rho2 = x * x + y * y;
      const float z = s.map.at(ix, iy);
      if (rho2 >= 0.25 * 0.25) {
        EXPECT_EQ(z, 0.5f);
        continue;
      }
      const double depth = std::sqrt(0.25 * 0.25 - rho2);
      if (depth / 0.25 < std::cos(75 * M_PI / 180)) {
        EXPECT_TRUE(std::isnan(z)) << "flank steeper than 75 degrees must be missing";
        ++steep;
        continue;
      }
      EXPECT_NEAR(z, 0.5 - depth, 3e-8);  // float rounding at 0.5 mm
      ++checked;
    }
  }
  EXPECT_GT(checked, 7000);
  EXPECT_GT(steep, 100);
}

TEST(CalotteSurface, TiltedFaceCarriesItsCalottes) {
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.05;  // the truth does not depend on the pixels; coarse ones keep the test quick
  o.slope_x = 0.02;
  o.slope_y = -0.01;
  o.z0_mm = -50.0;
  o.depth_mm = 0.1;  // a shallow cap: the sphere's centre 0.15 mm above the face, along its normal
  const Artefact bar = CalotteBar17();
  const CalotteSurface s = RenderCalotteSurface(bar, o);
  ASSERT_EQ(s.truth.size(), 17u);
  const Eigen::Vector3d normal = Eigen::Vector3d(-0.02, 0.01, 1.0).normalized();
  for (const Calotte& c : s.truth) {
    EXPECT_NEAR(c.radius_mm, 1.0, 0.0);
    // Back along the normal by (radius - depth) lands on the face.
    const Eigen::Vector3d foot = c.centre - 0.9 * normal;
    EXPECT_NEAR(foot.z(), -50.0 + 0.02 * foot.x() - 0.01 * foot.y(), 1e-12);
  }
  EXPECT_NEAR(s.truth[16].centre.x() - s.truth[0].centre.x(), 160.0, 1e-9);
}

TEST(CalotteSurface, NoiseDropoutsSpikesAndBurrsAsAsked) {
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.01;
  o.margin_mm = 2.0;
  o.noise_sigma_mm = 2e-4;
  o.missing_fraction = 0.1;
  o.burr_height_mm = 0.003;
  o.seed = 17;
  const CalotteSurface s = RenderCalotteSurface(SingleCalotte(0.25), o);
  double sum = 0, sum2 = 0;
  std::size_t face = 0, missing = 0, all = 0;
  float highest = -1;
  for (int iy = 0; iy < s.map.size_y; ++iy) {
    for (int ix = 0; ix < s.map.size_x; ++ix) {
      const float z = s.map.at(ix, iy);
      const double rho = std::hypot(X(s.map, ix), Y(s.map, iy));
      if (rho > 0.5) {  // the face, beyond the burr
        ++all;
        if (std::isnan(z)) {
          ++missing;
          continue;
        }
        sum += z, sum2 += z * z, ++face;
      } else if (std::isfinite(z)) {
        highest = std::max(highest, z);
      }
    }
  }
  const double mean = sum / face, sd = std::sqrt(sum2 / face - mean * mean);
  EXPECT_NEAR(mean, 0.0, 5 * 2e-4 / std::sqrt(face));
  EXPECT_NEAR(sd, 2e-4, 0.02 * 2e-4);
  const double p = static_cast<double>(missing) / all;
  EXPECT_NEAR(p, 0.1, 4 * std::sqrt(0.1 * 0.9 / all));
  EXPECT_NEAR(highest, 0.003, 5 * 2e-4) << "the burr's crest";

  // The same seed gives the same bytes; another seed other bytes.
  const CalotteSurface again = RenderCalotteSurface(SingleCalotte(0.25), o);
  ASSERT_EQ(again.map.z_mm.size(), s.map.z_mm.size());
  EXPECT_EQ(std::memcmp(again.map.z_mm.data(), s.map.z_mm.data(), s.map.z_mm.size() * sizeof(double)), 0);
  o.seed = 18;
  const CalotteSurface other = RenderCalotteSurface(SingleCalotte(0.25), o);
  EXPECT_NE(std::memcmp(other.map.z_mm.data(), s.map.z_mm.data(), s.map.z_mm.size() * sizeof(double)), 0);
}

TEST(CalotteSurface, RejectsImpossibleOptions) {
  CalotteSurfaceOptions o;
  o.depth_mm = 0.3;  // deeper than the 0.25 mm radius: an undercut
  EXPECT_THROW(RenderCalotteSurface(SingleCalotte(0.25), o), std::invalid_argument);
  o = {};
  o.dx_mm = 0;
  EXPECT_THROW(RenderCalotteSurface(SingleCalotte(0.25), o), std::invalid_argument);
  o = {};
  o.missing_fraction = 1.0;
  EXPECT_THROW(RenderCalotteSurface(SingleCalotte(0.25), o), std::invalid_argument);
  o = {};
  o.dx_mm = o.dy_mm = 1e-5;  // the bar at 10 nm pixels: far too many points
  EXPECT_THROW(RenderCalotteSurface(CalotteBar17(), o), std::invalid_argument);
}

}  // namespace
}  // namespace fvm::artefacts
