#include "workflows/focus.h"

#include <cmath>

#include "core/statistics.h"
#include "imaging/tile_registration.h"  // SetImagingThreads

namespace fvm::workflows {
namespace {

double MedianOrZero(const std::vector<float>& values) { return values.empty() ? 0.0 : HighMedian(values); }

}  // namespace

FocusSummary ReconstructFocus(std::vector<imaging::FocusStackEntry> entries, const FocusOptions& options,
                              const std::function<void()>& on_image) {
  options.focus.Check();
  FocusSummary s;
  s.entries = std::move(entries);
  s.slice_units = s.entries.front().line == 0 && !options.z_step_mm;
  imaging::SetImagingThreads(options.threads);
  imaging::FocusStackFilesOptions files;
  files.focus = options.focus;
  files.align = options.align;
  files.colour = options.colour;
  s.read = imaging::ReconstructFocusStackFiles(s.entries, files, on_image);
  const imaging::FocusResult& result = s.read.focus;
  s.map = result.height;
  if (s.slice_units) s.map.source += "; heights in slice units (no z step given)";
  s.stats = imaging::ComputeStats(s.map);
  std::vector<float> valid_quality, valid_u;
  for (std::size_t i = 0; i < s.map.z_mm.size(); ++i) {
    if (std::isfinite(s.map.z_mm[i])) valid_quality.push_back(result.quality[i]);
  }
  for (float u : result.u_z_mm) {
    if (std::isfinite(u)) valid_u.push_back(u);
  }
  s.median_quality = MedianOrZero(result.quality);
  s.median_valid_quality = MedianOrZero(valid_quality);
  s.median_u = MedianOrZero(valid_u);
  return s;
}

}  // namespace fvm::workflows
