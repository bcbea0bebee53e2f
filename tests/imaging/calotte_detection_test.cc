// Calotte detection and numbering on height maps rendered from the artefacts with a recorded truth.

#include "imaging/calotte_detection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/calotte_surface.h"
#include "core/input_error.h"
#include "imaging/calotte_numbering.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {
namespace {

using artefacts::CalotteSurface;
using artefacts::CalotteSurfaceOptions;

std::vector<NominalCalotte> Nominal(const artefacts::Artefact& artefact) {
  std::vector<NominalCalotte> nominal;
  for (const auto& c : artefact.calottes) nominal.push_back({c.id, c.centre.head<2>()});
  return nominal;
}

std::map<int, Eigen::Vector3d> TruthById(const CalotteSurface& surface) {
  std::map<int, Eigen::Vector3d> truth;
  for (const auto& c : surface.truth) truth[c.id] = c.centre;
  return truth;
}

// The 6 x 6 grid as the target asks: noise, missing points, a tilted face, plus spikes and burrs, placed
// on the stage where the published study measured it ([Pérez 2019] Table 1) and turned by a degree.
//
// Why 0.1 um is achievable here: the calottes are 0.5 mm hemispheres whose flanks beyond 75 degrees the optics
// cannot see, leaving a disc of 0.48 mm; at 10 um pixels that is ~1800 heights per calotte. With sigma_z = 0.1
// um (the 10x lens' vertical resolution, [Pérez thesis] Table 5.2) the Cramer-Rao bound of a centre is 2.4 nm in x, y
// and 6.5 nm in z (checked below), so 0.1 um is 15 bounds in z: room for 36 x 3 coordinates, dropouts and trimmed
// spikes. With the 5x lens (0.41 um) the bound in z would be 27 nm and 0.1 um only 3.7 bounds: not achievable for all
// 108 coordinates, which is why the target names the noise.
CalotteSurfaceOptions GridOptions() {
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.01;
  o.margin_mm = 0.5;
  o.rotation_rad = 1.0 * M_PI / 180;
  o.offset_mm = Eigen::Vector2d(-154.5487, -115.4767);
  o.z0_mm = -50.3624;
  o.slope_x = 0.01;  // 0.57 degrees
  o.slope_y = -0.005;
  o.noise_sigma_mm = 1e-4;
  o.missing_fraction = 0.05;
  o.spike_fraction = 0.001;
  o.spike_height_mm = 0.02;
  o.burr_height_mm = 0.002;
  o.burr_width_mm = 0.01;
  o.seed = 4;
  return o;
}

TEST(CalotteDetection, Grid6x6AllFoundNumberedAndWithinATenthOfAMicrometre) {
  const artefacts::Artefact grid = artefacts::CalotteGrid6x6();
  const CalotteSurface surface = artefacts::RenderCalotteSurface(grid, GridOptions());
  CalotteDetection detection = DetectCalottes(surface.map);
  ASSERT_EQ(detection.calottes.size(), 36u);
  EXPECT_NEAR(detection.face.b, 0.01, 1e-6);
  EXPECT_NEAR(detection.face.c, -0.005, 1e-6);
  EXPECT_NEAR(detection.face.sigma_mm, 1e-4, 1e-5);

  NumberCalottes(detection, Nominal(grid));
  ASSERT_EQ(detection.calottes.size(), 36u);
  const auto truth = TruthById(surface);
  double worst = 0;
  for (std::size_t i = 0; i < 36; ++i) {
    const DetectedCalotte& c = detection.calottes[i];
    ASSERT_EQ(c.id, static_cast<int>(i) + 1);
    const Eigen::Vector3d error = c.fit.centre_mm - truth.at(c.id);
    worst = std::max(worst, error.norm());
    EXPECT_LT(error.norm(), 1e-4) << "calotte " << c.id << " off by " << error.transpose() * 1e3 << " um";
    EXPECT_NEAR(c.fit.radius_mm, 0.25, 1e-4);
    EXPECT_FALSE(c.at_border);
    EXPECT_GT(c.fit.points, 1500u);
    // The bound the comment above relies on, from this calotte's own points.
    const Eigen::Matrix3d reported = c.fit.centre_covariance_mm2;
    EXPECT_LT(std::sqrt(reported(2, 2)), 0.01e-3);
  }
  RecordProperty("worst_centre_error_nm", static_cast<int>(worst * 1e6));
}

TEST(CalotteDetection, Grid6x6BoundJustifiesTheTarget) {
  // The comment on GridOptions: the Cramer-Rao bound of one calotte's centre from its visible points.
  std::vector<Eigen::Vector3d> points;
  const double r = 0.25, reach = r * std::sin(75 * M_PI / 180);
  for (double y = -reach; y <= reach; y += 0.01) {
    for (double x = -reach; x <= reach; x += 0.01) {
      if (x * x + y * y <= reach * reach) points.emplace_back(x, y, -std::sqrt(r * r - x * x - y * y));
    }
  }
  const Eigen::MatrixXd crb =
      SphereCramerRaoBound(points, {Eigen::Vector3d::Zero(), r}, 1e-4 / std::sqrt(0.95), SphereResidual::kHeight);
  EXPECT_NEAR(std::sqrt(crb(0, 0)), 2.4e-6, 0.3e-6);
  EXPECT_NEAR(std::sqrt(crb(2, 2)), 6.5e-6, 0.6e-6);
  EXPECT_LT(4 * std::sqrt(crb(2, 2)), 1e-4 / 3);
}

TEST(CalotteDetection, NoiseFreeRenderedCapWithinOneNanometre) {
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.005;
  o.offset_mm = Eigen::Vector2d(12.3456, -7.891);
  o.z0_mm = 0.1;
  o.slope_x = 0.02;
  const CalotteSurface surface = artefacts::RenderCalotteSurface(artefacts::SingleCalotte(0.25), o);
  const CalotteDetection detection = DetectCalottes(surface.map);
  ASSERT_EQ(detection.calottes.size(), 1u);
  EXPECT_LT((detection.calottes[0].fit.centre_mm - surface.truth[0].centre).norm(), 1e-6);
}

TEST(CalotteDetection, Bar17NumberedAlongTheBarAndAmbiguityIsAnError) {
  const artefacts::Artefact bar = artefacts::CalotteBar17();
  CalotteSurfaceOptions o;
  o.dx_mm = o.dy_mm = 0.02;
  o.margin_mm = 0.5;
  o.depth_mm = 0.5;           // a ball-nose cap: 1 mm radius, 0.5 mm deep, 1.7 mm across
  o.rotation_rad = M_PI / 2;  // the bar along y
  o.noise_sigma_mm = 2e-4;
  o.missing_fraction = 0.02;
  o.seed = 9;
  const CalotteSurface surface = artefacts::RenderCalotteSurface(bar, o);
  CalotteDetection detection = DetectCalottes(surface.map);
  ASSERT_EQ(detection.calottes.size(), 17u);

  // Turned by 90 degrees, the bar fits the layout at +90 and -90 alike: numbering would be a guess.
  std::vector<Eigen::Vector2d> found;
  for (const auto& c : detection.calottes) found.push_back(c.fit.centre_mm.head<2>());
  try {
    MatchLayout(found, Nominal(bar));
    FAIL() << "no error for a bar at 90 degrees";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("--rotation-deg"));
  }

  LayoutMatchOptions hint;
  hint.expected_rotation_rad = M_PI / 2;
  const LayoutMatch match = MatchLayout(found, Nominal(bar), hint);
  EXPECT_EQ(match.matched, 17);
  EXPECT_NEAR(match.rotation_rad, M_PI / 2, 1e-5);
  EXPECT_NEAR(match.scale, 1.0, 1e-6);
  EXPECT_LT(match.rms_mm, 1e-4);
  NumberCalottes(detection, Nominal(bar), hint);
  const auto truth = TruthById(surface);
  for (const auto& c : detection.calottes) {
    EXPECT_LT((c.fit.centre_mm - truth.at(c.id)).norm(), 2e-4) << "calotte " << c.id;
  }
  // Calotte 1 at the bar's start: y = 0 once turned; 17 at y = 160 mm.
  EXPECT_NEAR(detection.calottes.front().fit.centre_mm.y(), 0.0, 1e-3);
  EXPECT_NEAR(detection.calottes.back().fit.centre_mm.y(), 160.0, 1e-3);
}

// An artefact edge (the table 2 mm below a third of the map), a calotte cut by the map's border, and a speck:
// the edge and the speck are rejected with a reason, the cut calotte is kept and flagged.
TEST(CalotteDetection, EdgesBordersAndSpecks) {
  CalotteSurfaceOptions o = GridOptions();
  o.spike_fraction = 0;
  o.rotation_rad = 0;  // square to the map, so that one cut halves a whole column
  const CalotteSurface surface = artefacts::RenderCalotteSurface(artefacts::CalotteGrid6x6(), o);
  HeightMap map = surface.map;
  // Crop through the middle of the last column of calottes: x beyond their centres is gone.
  const auto truth = TruthById(surface);
  const int keep_x = static_cast<int>((truth.at(6).x() - map.x0_mm) / map.dx_mm) + 1;
  HeightMap cropped = map;
  cropped.size_x = keep_x;
  cropped.z_mm.clear();
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < keep_x; ++ix) cropped.z_mm.push_back(map.at(ix, iy));
  }
  // The table below the part's edge along the top of the map (largest y), 2 mm down.
  for (int iy = cropped.size_y - 40; iy < cropped.size_y; ++iy) {
    for (int ix = 0; ix < cropped.size_x; ++ix) cropped.at(ix, iy) -= 2.0f;
  }
  // A speck of dust's shadow: 0.1 mm pit of 3 x 3 pixels between calottes.
  const int sx = static_cast<int>((truth.at(1).x() + 2.0 - cropped.x0_mm) / cropped.dx_mm);
  const int sy = static_cast<int>((truth.at(1).y() - cropped.y0_mm) / cropped.dy_mm);
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) cropped.at(sx + dx, sy + dy) -= 0.1f;
  }

  const CalotteDetection detection = DetectCalottes(cropped);
  EXPECT_NEAR(detection.face.b, 0.01, 1e-6) << "the table must not tilt the face";
  ASSERT_EQ(detection.calottes.size(), 36u);
  int at_border = 0;
  for (const auto& c : detection.calottes) {
    if (!c.at_border) continue;
    ++at_border;
    // Half a cap still pins its sphere, less well.
    double best = 1e9;
    for (const auto& [id, centre] : truth) best = std::min(best, (c.fit.centre_mm - centre).norm());
    EXPECT_LT(best, 1e-3);
  }
  EXPECT_EQ(at_border, 6);
  ASSERT_EQ(detection.rejected.size(), 1u) << "the edge (the speck is too small to be listed)";
  EXPECT_THAT(detection.rejected[0].reason, testing::HasSubstr("larger than a calotte"));
}

TEST(CalotteDetection, PartialViewOfTheGridCannotBeNumbered) {
  std::vector<Eigen::Vector2d> found = {{0, 0}, {4, 0}, {0, -4}, {4, -4}};  // any 2 x 2 block of the grid
  try {
    MatchLayout(found, Nominal(artefacts::CalotteGrid6x6()));
    FAIL() << "no error for a partial view";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("more than one place"));
  }
}

TEST(CalotteDetection, BadMapsAreClearErrors) {
  HeightMap empty;
  empty.size_x = 4;
  empty.size_y = 3;
  empty.dx_mm = empty.dy_mm = 0.01;
  empty.z_mm.assign(12, NAN);
  try {
    DetectCalottes(empty);
    FAIL() << "no error for an all-NaN map";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("no valid point"));
  }
  HeightMap no_pixel = empty;
  no_pixel.dx_mm = 0;
  no_pixel.z_mm.assign(12, 0.0f);
  EXPECT_THROW(DetectCalottes(no_pixel), InputError);
  HeightMap wrong_size = empty;
  wrong_size.z_mm.resize(5);
  EXPECT_THROW(DetectCalottes(wrong_size), InputError);
  // A flat map has no calottes: an empty result, not an error.
  HeightMap flat = no_pixel;
  flat.dx_mm = 0.01;
  EXPECT_TRUE(DetectCalottes(flat).calottes.empty());
}

}  // namespace
}  // namespace fvm::imaging
