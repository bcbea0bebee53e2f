#include "artefacts/batch_observations.h"

namespace fvm::artefacts {

ObservationSet Observations(const Batch& batch, const std::vector<std::string>& placements) {
  ObservationSet set;
  for (const std::string& name : placements) {
    const Placement& p = batch.Get(name);
    const int group = static_cast<int>(set.groups.size());
    set.groups.push_back(name);
    set.anchors.push_back(stage::FirstTile(p.free));
    for (size_t i = 0; i < p.ids.size(); ++i) set.observations.push_back({p.free[i], p.stitched[i], group});
  }
  return set;
}

}  // namespace fvm::artefacts
