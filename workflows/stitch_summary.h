#pragma once
// What `fvm stitch` tells its user about a stitched layout (workflows/stitch_layout.h): the --json document (tiles,
// pairs, the stage model, the loops' verdicts, the field), the printed text and the report's data, the same in
// Python's fvm.stitch. The command adds only the lines naming its files.

#include "workflows/stitch_layout.h"
#include "workflows/summary.h"

namespace fvm::workflows {

Summary Summarize(const StitchedLayout& stitched);

// What --report DIR draws (report/stitch_report.h): the tiles with u, the pairs, the loops' misclosures, the field.
report::StitchReportData StitchReport(const StitchedLayout& stitched);

}  // namespace fvm::workflows
