#pragma once
// What `fvm stitch` tells its user about a stitched layout (workflows/stitch_layout.h): the --json document (tiles,
// pairs, the stage model, the loops' verdicts, the field) and the printed text, the same in Python's fvm.stitch.
// The command adds only the lines naming its files.

#include "workflows/stitch_layout.h"
#include "workflows/summary.h"

namespace fvm::workflows {

Summary Summarize(const StitchedLayout& stitched);

}  // namespace fvm::workflows
