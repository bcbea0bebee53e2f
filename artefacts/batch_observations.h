#pragma once
// The pairs of a batch as identification observations: one group per placement, anchored at its first tile.

#include <string>
#include <vector>

#include "artefacts/batch.h"
#include "stage/identification.h"

namespace fvm::artefacts {

struct ObservationSet {
  std::vector<stage::Observation> observations;
  std::vector<Eigen::Vector3d> anchors;  // first tile of each group (stage::FirstTile of its free centres)
  std::vector<std::string> groups;       // placement name of each group
};

// Throws InputError when a name is not a placement of the batch.
ObservationSet Observations(const Batch& batch, const std::vector<std::string>& placements);

}  // namespace fvm::artefacts
