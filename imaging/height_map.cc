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
  }
  return stats;
}

}  // namespace fvm::imaging
