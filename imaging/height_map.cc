#include "imaging/height_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fvm::imaging {

HeightMapStats ComputeStats(const HeightMap& map) {
  HeightMapStats stats;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (double z : map.z_mm) {
    if (!std::isfinite(z)) continue;
    ++stats.valid_points;
    lo = std::min(lo, static_cast<double>(z));
    hi = std::max(hi, static_cast<double>(z));
  }
  if (stats.valid_points > 0) {
    stats.z_min_mm = lo;
    stats.z_max_mm = hi;
    // Two passes, the second about the mean: a map far from z = 0 keeps the digits of its roughness.
    long double sum = 0;
    for (double z : map.z_mm) {
      if (std::isfinite(z)) sum += z;
    }
    const long double mean = sum / static_cast<long double>(stats.valid_points);
    long double sum2 = 0;
    for (double z : map.z_mm) {
      if (std::isfinite(z)) sum2 += (z - mean) * (z - mean);
    }
    stats.sq_mm = static_cast<double>(std::sqrt(sum2 / static_cast<long double>(stats.valid_points)));
  }
  return stats;
}

}  // namespace fvm::imaging
