#include "artefacts/geometry/artefact.h"

#include <gtest/gtest.h>

namespace fvm::artefacts {
namespace {

TEST(Artefact, BarHas17CalottesAt10mmPitch) {
  const Artefact bar = CalotteBar17();
  ASSERT_EQ(bar.calottes.size(), 17u);
  EXPECT_EQ(bar.calottes.back().id, 17);
  EXPECT_DOUBLE_EQ((bar.calottes.back().centre - bar.calottes.front().centre).norm(), 160.0);
  EXPECT_DOUBLE_EQ(bar.calottes[0].radius_mm, 1.0);
}

TEST(Artefact, GridCornersAreNumbered1_6_31_36) {
  const Artefact grid = CalotteGrid6x6();
  ASSERT_EQ(grid.calottes.size(), 36u);
  const auto centre = [&](int id) { return grid.calottes[static_cast<size_t>(id - 1)].centre; };
  EXPECT_DOUBLE_EQ((centre(6) - centre(1)).norm(), 20.0);   // the 20 mm of [Pérez 2019] Table 1
  EXPECT_DOUBLE_EQ((centre(31) - centre(1)).norm(), 20.0);  // the Y-direction distance of Table 2
  EXPECT_GT(centre(6).x(), centre(1).x());                   // left to right
  EXPECT_LT(centre(31).y(), centre(1).y());                  // top to bottom
}

}  // namespace
}  // namespace fvm::artefacts
