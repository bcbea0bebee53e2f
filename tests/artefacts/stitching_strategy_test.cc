#include "artefacts/simulation/stitching_strategy.h"

#include <gtest/gtest.h>

#include "stage/fvm_stage_models.h"
#include "tests/support/published_grid_row.h"

namespace fvm::artefacts {
namespace {

using testing::kPublishedRowFirst;
using testing::kPublishedRowLast;

std::vector<StrategyResult> WithScaleError(double xtx1_mm) {
  stage::ParameterLayout layout = stage::FvmModelLayout("9");
  std::vector<double> values(static_cast<size_t>(layout.NumFree()), 0.0);
  values[static_cast<size_t>(layout.FreeIndexOf("xTx1"))] = xtx1_mm;  // positioning error of X, linear in x
  return SimulateStitchingStrategies(layout, values, kPublishedRowFirst, kPublishedRowLast);
}

TEST(StitchingStrategy, ReproducesThePublishedPattern) {
  // xTx1 = 0.075 mm per 100 mm of travel: 15 um over the 20 mm row, the size of Table 1's cases b, e, f.
  const std::vector<StrategyResult> r = WithScaleError(0.075);
  ASSERT_EQ(r.size(), 6u);
  const auto error = [&](char id) { return r[static_cast<size_t>(id - 'a')].distance_error_um; };
  EXPECT_NEAR(error('a'), 0.0, 1e-6);  // everything registered to the first tile: no stage error at all
  // Only the end tiles, or the last encoder-placed tile at the end: the whole error of the row (first order:
  // 0.075 mm x 20 mm / 100 mm = 15 um, less the y component of the oblique row).
  for (char id : {'b', 'e', 'f'}) EXPECT_NEAR(std::abs(error(id)), 15.0, 0.1) << id;
  // The error grows with the distance from the first tile to the last one placed by encoders: 17 tiles at
  // 1.62 mm x 0.8; c re-anchors at tile 2 (2/16 of the row), d at tile 9 (9/16). Published: -1.5, -8.9, -14.8.
  EXPECT_NEAR(error('c') / error('e'), 2.0 / 16.0, 0.005);
  EXPECT_NEAR(error('d') / error('e'), 9.0 / 16.0, 0.005);
  EXPECT_EQ(r[0].encoder_tiles, std::vector<int>{0});
  EXPECT_EQ(r[2].encoder_tiles, (std::vector<int>{0, 2}));
}

TEST(StitchingStrategy, ErrorScalesWithTheStageError) {
  const double full = WithScaleError(0.075)[1].distance_error_um;
  EXPECT_NEAR(WithScaleError(0.0375)[1].distance_error_um, full / 2, 0.01);
  EXPECT_NEAR(WithScaleError(0.0)[1].distance_error_um, 0.0, 1e-6);
}

TEST(StitchingStrategy, RejectsImpossibleOptions) {
  stage::ParameterLayout layout = stage::FvmModelLayout("9");
  const std::vector<double> zeros(static_cast<size_t>(layout.NumFree()), 0.0);
  EXPECT_THROW(SimulateStitchingStrategies(layout, zeros, kPublishedRowFirst, kPublishedRowFirst), std::invalid_argument);
  EXPECT_THROW(SimulateStitchingStrategies(layout, zeros, kPublishedRowFirst, kPublishedRowLast, StrategyOptions{1.62, 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace fvm::artefacts
