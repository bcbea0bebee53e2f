#include "artefacts/tracker_observations.h"

namespace fvm::artefacts {

std::vector<stage::Observation> TrackerObservations(const TrackerReadings& readings, const stage::TrackerNoise* noise) {
  std::vector<stage::Observation> out;
  for (const TrackerReading& r : readings.points) {
    stage::Observation o;
    o.command = r.nominal;
    o.measured = r.measured;
    if (noise != nullptr) o.covariance = r.covariance ? *r.covariance : noise->Covariance(r.measured);
    o.tool = r.tool;
    out.push_back(o);
  }
  return out;
}

}  // namespace fvm::artefacts
