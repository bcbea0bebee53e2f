#pragma once
// What a laser tracker can see from where it stands: the check that refuses readings it could not have made (fvm
// verify on real data) and keeps simulated ones and placements within reach.

#include <string>
#include <vector>

#include "artefacts/io/tracker_readings.h"
#include "stage/pose.h"

namespace fvm::artefacts {

// What a tracker can see. Defaults: elevation -60..+77 deg (a typical tracker head's vertical travel) and range
// up to 40 m. The elevation is taken against the horizontal (the machine's xy plane, z up) at the tracker's
// position, not in the frame its readings are expressed in: a tracker head stands levelled, while the frame of a
// pose such as [IJSIMM 2016] Table I (rotations of up to 65 deg) is a coordinate frame, not a tilt of the head. In the
// tracker's own frame position 4 would put 24 of the 96 mesh points below -60 deg.
struct TrackerLimits {
  double min_elevation_deg = -60.0;
  double max_elevation_deg = 77.0;
  double max_range_mm = 40'000.0;
};
// One message per point out of the limits ("P0007: elevation 81.2 deg above the tracker's +77 deg"), empty when
// all are in. `readings` are in the frame of `tracker` (its pose in the machine frame).
std::vector<std::string> PointsBeyondTrackerLimits(const TrackerReadings& readings, const stage::Pose& tracker,
                                                   const TrackerLimits& limits = {});

}  // namespace fvm::artefacts
