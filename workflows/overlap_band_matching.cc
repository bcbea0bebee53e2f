#include "workflows/overlap_band_matching.h"

#include <algorithm>
#include <cmath>

namespace fvm::workflows {

imaging::CorrespondenceOptions BandMatching(imaging::CorrespondenceOptions matching, double band_px) {
  if (band_px >= 4.0 * matching.window_px) return matching;
  int window = static_cast<int>(std::floor(band_px / 4.0));
  if (window % 2 == 0) --window;
  matching.window_px = std::max(7, window);
  matching.pyramid_levels = std::min(matching.pyramid_levels, 1);
  matching.grid_step_px = std::max(2, std::min(matching.grid_step_px, static_cast<int>(std::floor(band_px / 10.0))));
  return matching;
}

}  // namespace fvm::workflows
