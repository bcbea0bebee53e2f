#include "artefacts/batch_observations.h"

namespace fvm::artefacts {

stage::MeasurementSet Observations(const Batch& batch, const std::vector<std::string>& placements) {
  stage::MeasurementSet set;
  bool timed = true;
  for (const std::string& name : placements) {
    const Placement& p = batch.Get(name);
    const int group = static_cast<int>(set.groups.size());
    set.groups.push_back(name);
    set.anchors.push_back(stage::FirstTile(p.free));
    timed = timed && p.t_s.size() == p.ids.size();
    for (size_t i = 0; i < p.ids.size(); ++i) {
      set.observations.push_back({p.free[i], p.stitched[i], group});
      set.labels.push_back(name + ":" + std::to_string(p.ids[i]));
      if (timed) set.t_s.push_back(p.t_s[i]);
    }
  }
  if (!timed) set.t_s.clear();
  return set;
}

}  // namespace fvm::artefacts
