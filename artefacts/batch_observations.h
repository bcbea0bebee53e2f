#pragma once
// The pairs of a batch as identification observations: one group per placement, anchored at its first tile.

#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "stage/identification.h"

namespace fvm::artefacts {

// One group per placement, anchored at its first tile; times when every placement has them. Throws InputError
// when a name is not a placement of the batch.
stage::MeasurementSet Observations(const Batch& batch, const std::vector<std::string>& placements);

}  // namespace fvm::artefacts
