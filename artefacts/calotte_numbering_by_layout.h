#pragma once
// The calottes found on a surface numbered as the artefact numbers them (imaging/calotte_numbering.h): what
// `fvm fit --artefact` and a batch of raw exports share.

#include "artefacts/geometry/artefact.h"
#include "imaging/calotte_detection.h"
#include "imaging/calotte_numbering.h"

namespace fvm::artefacts {

// Matches the found centres to the artefact's nominal layout and gives each calotte its id. `retry_turned`: when
// the match is ambiguous (a bar along y fits turned by +90 and -90 degrees equally), expect a turn 45 degrees on,
// which picks one of the two; a partial view of a regular pattern stays ambiguous and throws the first message.
// Throws InputError as imaging::MatchLayout does.
imaging::LayoutMatch NumberByLayout(imaging::CalotteDetection& detection, const Artefact& artefact,
                                    const imaging::LayoutMatchOptions& match, bool retry_turned = false);

}  // namespace fvm::artefacts
