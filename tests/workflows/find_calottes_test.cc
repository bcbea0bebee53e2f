#include "workflows/find_calottes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "artefacts/simulation/calotte_surface.h"
#include "core/input_error.h"

namespace fvm::workflows {
namespace {

// The grid of 36 calottes turned by 0.3 degrees on a tilted face with 0.5 um height noise: every calotte found,
// numbered by the grid's layout, its centre within 0.5 um of the truth in x and y (the fits' standard
// uncertainties are tens of nm at 10 um pixels) and the turn recovered within 0.01 degrees.
TEST(FindCalottes, FindsAndNumbersEveryCalotteOfTheGrid) {
  artefacts::CalotteSurfaceOptions render;
  render.dx_mm = render.dy_mm = 0.02;
  render.rotation_rad = 0.3 * M_PI / 180;
  render.slope_x = 1e-3;
  render.noise_sigma_mm = 0.5e-3;
  render.seed = 7;
  const artefacts::Artefact grid = artefacts::CalotteGrid6x6();
  const artefacts::CalotteSurface surface = artefacts::RenderCalotteSurface(grid, render);
  FindCalottesOptions options;
  options.artefact = grid;
  const FoundCalottes found = FindCalottes(imaging::Surface{imaging::SurfaceFormat::kX3p, surface.map, std::nullopt}, options, "grid.x3p");
  ASSERT_EQ(found.detection.calottes.size(), 36u);
  ASSERT_TRUE(found.layout.has_value());
  EXPECT_NEAR(found.layout->rotation_rad * 180 / M_PI, 0.3, 0.01);
  EXPECT_EQ(found.method, "height map");
  ASSERT_TRUE(found.map.has_value());
  for (const auto& c : found.detection.calottes) {
    const auto truth = std::find_if(surface.truth.begin(), surface.truth.end(), [&](const auto& t) { return t.id == c.id; });
    ASSERT_NE(truth, surface.truth.end()) << c.id;
    EXPECT_LT((c.fit.centre_mm.head<2>() - truth->centre.head<2>()).norm(), 0.5e-3) << "calotte " << c.id;
  }
}

TEST(FindCalottes, AFlatSurfaceIsRefusedNamingTheFile) {
  imaging::HeightMap flat;
  flat.size_x = flat.size_y = 200;
  flat.dx_mm = flat.dy_mm = 0.01;
  flat.z_mm.assign(200 * 200, 0.0);
  try {
    FindCalottes(imaging::Surface{imaging::SurfaceFormat::kX3p, flat, std::nullopt}, {}, "flat.x3p");
    FAIL() << "a flat surface gave calottes";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("flat.x3p: no calotte found", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace fvm::workflows
