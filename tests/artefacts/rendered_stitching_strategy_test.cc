// The stitching strategies played on rendered, registered tiles agree with the coordinate model up to the
// registration and fit noise, and show the published pattern.

#include "artefacts/simulation/rendered_stitching_strategy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "stage/fvm_stage_models.h"
#include "tests/support/published_grid_row.h"

namespace fvm::artefacts {
namespace {

using testing::kPublishedRowFirst;
using testing::kPublishedRowLast;

TEST(RenderedStitchingStrategy, AgreesWithTheCoordinateModelWithinRegistrationNoise) {
  // xTx1 = 0.075 mm per 100 mm of travel: 15 um over the row, the size of Table 1's cases b, e, f.
  const stage::ParameterLayout layout = stage::FvmModelLayout("9");
  std::vector<double> values(static_cast<size_t>(layout.NumFree()), 0.0);
  values[static_cast<size_t>(layout.FreeIndexOf("xTx1"))] = 0.075;
  RenderedStrategyOptions options;
  options.tile_px = 256;  // 6.3 um pixels: the 15 um error is 2.4 px, the registration noise a few hundredths
  for (const std::uint64_t seed : {1u, 2u}) {
    options.seed = seed;
    const RenderedStrategies r = SimulateRenderedStrategies(layout, values, kPublishedRowFirst, kPublishedRowLast, options);
    ASSERT_EQ(r.cases.size(), 6u);
    EXPECT_EQ(r.row_tiles, 17);
    EXPECT_EQ(r.rejected_pairs, 0);
    EXPECT_LT(r.pair_rms_px, 0.1);  // the registration target of issue 5
    // Case a chains all 16 pairs. However bias and noise mix, the sum of k pair errors is at most k times their
    // rms (Cauchy-Schwarz), so 16 x rms bounds every case; plus 0.1 um for the two sphere fits (0.1 um height
    // noise over ~2000 points each gives a few nm). A sign or frame error in the chain costs microns per pair.
    const double bound_um = 16.0 * r.pair_rms_px * r.pixel_mm * 1e3 + 0.1;
    for (const RenderedStrategyResult& c : r.cases) {
      EXPECT_NEAR(c.result.distance_error_um, c.coordinates.distance_error_um, bound_um) << c.result.id << " seed " << seed;
      EXPECT_EQ(c.accepted_pairs, c.pairs) << c.result.id;
      std::printf("seed %d case %c: rendered %.2f um, coordinates %.2f um (bound %.2f)\n", static_cast<int>(seed),
                  c.result.id, c.result.distance_error_um, c.coordinates.distance_error_um, bound_um);
    }
    // The published pattern from images: c re-anchors at tile 2, d at tile 9 (of 16), e at the last.
    const auto error = [&](char id) { return r.cases[static_cast<size_t>(id - 'a')].result.distance_error_um; };
    EXPECT_LT(std::abs(error('c')), std::abs(error('d')));
    EXPECT_LT(std::abs(error('d')), std::abs(error('e')));
    EXPECT_EQ(r.cases[2].result.encoder_tiles, (std::vector<int>{0, 2}));
    EXPECT_EQ(r.cases[1].result.encoder_tiles, (std::vector<int>{0, 16}));
  }
}

TEST(RenderedStitchingStrategy, UnregistrableTilesFallBackToTheEncoders) {
  // Tiles without texture (a polished face: a texture of 1 count under 100 counts of sensor noise): every pair
  // is rejected, every tile sits where the encoders put it, and case a measures what case b measures: the full
  // stage error of the row.
  const stage::ParameterLayout layout = stage::FvmModelLayout("9");
  std::vector<double> values(static_cast<size_t>(layout.NumFree()), 0.0);
  values[static_cast<size_t>(layout.FreeIndexOf("xTx1"))] = 0.075;
  RenderedStrategyOptions options;
  options.tile_px = 128;
  options.camera.contrast = 1.0;
  options.camera.noise = 100.0;  // a fraction of the contrast
  const RenderedStrategies r = SimulateRenderedStrategies(layout, values, kPublishedRowFirst, kPublishedRowLast, options);
  EXPECT_EQ(r.rejected_pairs, r.row_tiles - 1);
  const RenderedStrategyResult& a = r.cases[0];
  EXPECT_EQ(a.accepted_pairs, 0);
  EXPECT_EQ(static_cast<int>(a.result.encoder_tiles.size()), r.row_tiles);
  EXPECT_NEAR(a.result.distance_error_um, r.cases[1].coordinates.distance_error_um, 0.1);
}

TEST(RenderedStitchingStrategy, RejectsACalotteLargerThanTheField) {
  const stage::ParameterLayout layout = stage::FvmModelLayout("9");
  const std::vector<double> zeros(static_cast<size_t>(layout.NumFree()), 0.0);
  RenderedStrategyOptions options;
  options.calotte_radius_mm = 1.0;  // 2 mm across, the 10x field is 1.62 mm
  EXPECT_THROW(SimulateRenderedStrategies(layout, zeros, kPublishedRowFirst, kPublishedRowLast, options), std::invalid_argument);
}

}  // namespace
}  // namespace fvm::artefacts
