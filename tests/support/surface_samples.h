#pragma once
// Height maps and clouds for the reader/writer tests: small, with invalid points, negative and tiny heights,
// an origin away from zero, so that a round trip that loses any of these shows.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

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
// mm, and z / 1000 * 1000 has no exact inverse for about 2 % of doubles (x3p_writer.cc writes the one that reads back
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

// A binary ISO 25178-71 SDF ("bISO-1.0") laid out byte by byte from the standard's header table, independently
// of imaging/io/sdf.cc: heights as float64 (DataType 7) in units of z_scale_m, little-endian.
inline std::string BinarySdf(int points, int profiles, double x_scale_m, double y_scale_m, double z_scale_m,
                             const std::vector<double>& values, unsigned char data_type = 7) {
  std::string bytes = "bISO-1.0";
  bytes += std::string("TEST      ", 10) + "010120240000" + "010120240000";
  const auto put = [&](const void* p, std::size_t n) { bytes.append(static_cast<const char*>(p), n); };
  const std::uint16_t np = static_cast<std::uint16_t>(points), nq = static_cast<std::uint16_t>(profiles);
  put(&np, 2), put(&nq, 2);
  const double resolution = 0;
  put(&x_scale_m, 8), put(&y_scale_m, 8), put(&z_scale_m, 8), put(&resolution, 8);
  bytes += std::string(1, '\0') + std::string(1, static_cast<char>(data_type)) + std::string(1, '\0');
  for (const double v : values) {
    if (data_type == 5) {
      const auto i = static_cast<std::int16_t>(v);
      put(&i, 2);
    } else {
      put(&v, 8);
    }
  }
  return bytes;
}

inline void ExpectSameGrid(const HeightMap& expected, const HeightMap& actual) {
  EXPECT_DOUBLE_EQ(actual.dx_mm, expected.dx_mm);
  EXPECT_DOUBLE_EQ(actual.dy_mm, expected.dy_mm);
  EXPECT_DOUBLE_EQ(actual.x0_mm, expected.x0_mm);
  EXPECT_DOUBLE_EQ(actual.y0_mm, expected.y0_mm);
}

}  // namespace fvm::imaging::testing
