#include "workflows/overlap_band_matching.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/input_error.h"

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

std::vector<size_t> AppendRegisteredSet(const std::vector<imaging::TileImage>& images,
                                        const std::vector<imaging::PairRegistration>& pairs,
                                        const imaging::TilePositions& positions, const imaging::FieldDistortion& guess,
                                        const imaging::CorrespondenceOptions& matching, const std::string& set,
                                        RegisteredOverlapPoints& points) {
  const int width = static_cast<int>(images.front().cols()), height = static_cast<int>(images.front().rows());
  if (points.width == 0) points.width = width, points.height = height;
  if (width != points.width || height != points.height) {
    throw InputError(fmt::format("{} has tiles of {} x {} px, the first {} x {}: one field is one objective and one "
                                 "camera", set, width, height, points.width, points.height));
  }
  const int base = static_cast<int>(points.initial.size());
  std::vector<imaging::OverlapToMatch> overlaps;
  std::vector<size_t> pair_of_overlap;
  for (size_t q = 0; q < pairs.size(); ++q) {
    if (pairs[q].accepted) overlaps.push_back({pairs[q].a, pairs[q].b, pairs[q].offset_px}), pair_of_overlap.push_back(q);
  }
  double band = std::numeric_limits<double>::infinity();
  for (const imaging::OverlapToMatch& o : overlaps) {
    band = std::min({band, width - std::abs(o.offset_px.x()), height - std::abs(o.offset_px.y())});
  }
  for (imaging::PairCorrespondences& p : imaging::MatchOverlaps(images, overlaps, guess, BandMatching(matching, band))) {
    p.a += base, p.b += base;
    points.matched.push_back(std::move(p));
  }
  for (size_t k = 0; k < images.size(); ++k) {
    points.initial.push_back(positions.positions_px[k]);
    points.fixed.push_back(positions.anchor[k] == static_cast<int>(k));
  }
  return pair_of_overlap;
}

}  // namespace fvm::workflows
