#include "workflows/find_calottes.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "artefacts/calotte_numbering_by_layout.h"
#include "artefacts/io/raw_export_batch.h"
#include "core/input_error.h"
#include "imaging/cloud_calotte_detection.h"
#include "imaging/point_cloud.h"

namespace fvm::workflows {

FoundCalottes FindCalottes(imaging::Surface surface, const FindCalottesOptions& options, const std::string& name) {
  FoundCalottes out;
  out.artefact = options.artefact;
  std::optional<imaging::PointCloud> cloud;
  if (surface.height_map) {
    out.map = std::move(surface.height_map);
  } else if (!surface.cloud->IsOrganised()) {
    cloud = std::move(surface.cloud);
  } else {
    out.map = imaging::CloudToHeightMap(*surface.cloud, name);
  }

  imaging::CalotteDetectionOptions search =
      out.artefact ? artefacts::CalotteSearchFor(*out.artefact) : imaging::CalotteDetectionOptions{};
  search.fit.fixed_radius_mm = options.radius_mm;
  search.fit.residual = options.residual;
  search.min_depth_mm = options.min_depth_mm;
  if (options.min_diameter_mm > 0) search.min_diameter_mm = options.min_diameter_mm;
  if (options.max_diameter_mm > 0) search.max_diameter_mm = options.max_diameter_mm;
  if (search.max_diameter_mm < search.min_diameter_mm) {
    throw InputError(fmt::format("--min-diameter-mm {} is larger than --max-diameter-mm {}", search.min_diameter_mm,
                                 search.max_diameter_mm));
  }
  try {
    if (out.map) {
      out.detection = imaging::DetectCalottes(*out.map, search);
    } else {
      imaging::CloudCalotteDetection found = imaging::DetectCalottesInCloud(*cloud, search, name);
      out.detection = std::move(found.detection);
      out.method = found.method;
    }
    if (out.detection.calottes.empty()) {
      std::string why;
      for (std::size_t i = 0; i < std::min<std::size_t>(out.detection.rejected.size(), 5); ++i) {
        const auto& r = out.detection.rejected[i];
        why += fmt::format("\n  at ({:.3f}, {:.3f}) mm: {}", r.centre_mm.x(), r.centre_mm.y(), r.reason);
      }
      if (out.detection.rejected.size() > 5) why += fmt::format("\n  and {} more", out.detection.rejected.size() - 5);
      throw InputError(fmt::format(
          "no calotte found: no round depression {}-{} mm across and more than {:.2f} um below the face{}{}",
          search.min_diameter_mm, search.max_diameter_mm, out.detection.min_depth_mm * 1e3,
          why.empty() ? "" : "; rejected:", why));
    }
    if (out.artefact) {
      imaging::LayoutMatchOptions match;
      if (options.rotation_deg) match.expected_rotation_rad = *options.rotation_deg * M_PI / 180.0;
      out.layout = artefacts::NumberByLayout(out.detection, *out.artefact, match);
    }
  } catch (const InputError& e) {
    throw InputError(name + ": " + e.what());
  }
  return out;
}

}  // namespace fvm::workflows
