#include "artefacts/tracker_sight.h"

#include <fmt/core.h>

#include <numbers>

#include "stage/tracker.h"

namespace fvm::artefacts {

std::vector<std::string> PointsBeyondTrackerLimits(const TrackerReadings& readings, const stage::Pose& tracker,
                                                   const TrackerLimits& limits) {
  const Eigen::Matrix3d to_machine = tracker.Rotation();
  std::vector<std::string> out;
  for (const TrackerReading& r : readings.points) {
    // The beam in machine axes (z up): the levelled head's range and elevation.
    const stage::Spherical s = stage::ToSpherical(to_machine * r.measured);
    const double elevation_deg = s.elevation_rad * 180.0 / std::numbers::pi;
    if (s.range_mm > limits.max_range_mm) {
      out.push_back(fmt::format("{}: range {:.0f} mm beyond the tracker's {:.0f} mm", r.id, s.range_mm,
                                limits.max_range_mm));
    } else if (elevation_deg > limits.max_elevation_deg) {
      out.push_back(fmt::format("{}: elevation {:.1f} deg above the tracker's {:+.0f} deg", r.id, elevation_deg,
                                limits.max_elevation_deg));
    } else if (elevation_deg < limits.min_elevation_deg) {
      out.push_back(fmt::format("{}: elevation {:.1f} deg below the tracker's {:+.0f} deg", r.id, elevation_deg,
                                limits.min_elevation_deg));
    }
  }
  return out;
}

}  // namespace fvm::artefacts
