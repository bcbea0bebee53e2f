#pragma once
// Laser-tracker readings as identification observations (fvm verify and its tests).

#include <vector>

#include "artefacts/io/tracker_readings.h"
#include "stage/identification.h"
#include "stage/tracker.h"

namespace fvm::artefacts {

// One observation per reading: commanded point, tracker reading, its covariance (zero when `noise` is null: equal
// weights; else the reading's own when the file gave one, as multilaterated points carry, otherwise the tracker's
// noise model's), and which tool.
std::vector<stage::Observation> TrackerObservations(const TrackerReadings& readings, const stage::TrackerNoise* noise);

}  // namespace fvm::artefacts
