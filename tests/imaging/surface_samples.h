#pragma once
// Height maps and clouds for the reader/writer tests: small, with invalid points, negative and tiny heights,
// an origin away from zero, so that a round trip that loses any of these shows.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging::testing {

inline HeightMap SampleMap(int size_x = 7, int size_y = 5) {
  HeightMap map;
  map.size_x = size_x;
  map.size_y = size_y;
  map.dx_mm = 0.00175;
  map.dy_mm = 0.0021;
  map.x0_mm = -12.5;
  map.y0_mm = 3.25;
  for (int iy = 0; iy < size_y; ++iy) {
    for (int ix = 0; ix < size_x; ++ix) {
      map.z_mm.push_back(static_cast<float>(0.0123 * std::sin(0.7 * ix + 1.3 * iy) - 0.004 + 1e-7 * ix * iy));
    }
  }
  map.z_mm[1] = std::numeric_limits<float>::quiet_NaN();
  map.z_mm[map.z_mm.size() / 2] = std::numeric_limits<float>::quiet_NaN();
  map.z_mm.back() = -0.0f;
  return map;
}

// Same grid, same invalid points, same heights to the last bit or two of a double: files hold metres and the map
// mm, and z / 1000 * 1000 has no exact inverse for about 2 % of doubles (x3p.cc writes the one that reads back
// exactly whenever there is one).
inline void ExpectSameHeights(const HeightMap& expected, const HeightMap& actual) {
  ASSERT_EQ(actual.size_x, expected.size_x);
  ASSERT_EQ(actual.size_y, expected.size_y);
  ASSERT_EQ(actual.z_mm.size(), expected.z_mm.size());
  for (size_t i = 0; i < expected.z_mm.size(); ++i) {
    if (std::isnan(expected.z_mm[i])) {
      EXPECT_TRUE(std::isnan(actual.z_mm[i])) << "point " << i;
    } else {
      EXPECT_DOUBLE_EQ(actual.z_mm[i], expected.z_mm[i]) << "point " << i;
    }
  }
}

inline void ExpectSameGrid(const HeightMap& expected, const HeightMap& actual) {
  EXPECT_DOUBLE_EQ(actual.dx_mm, expected.dx_mm);
  EXPECT_DOUBLE_EQ(actual.dy_mm, expected.dy_mm);
  EXPECT_DOUBLE_EQ(actual.x0_mm, expected.x0_mm);
  EXPECT_DOUBLE_EQ(actual.y0_mm, expected.y0_mm);
}

}  // namespace fvm::imaging::testing
