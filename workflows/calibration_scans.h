#pragma once
// The stitched calibration scans a scan calibration reads (`fvm calibrate --scan`): layouts `file,row,col,x,y[,z]` whose rows are the
// tiles in scan order with their encoder readings (mm, tile centre), and the tiles themselves; registered as
// chains (imaging::RegisterTileChain). Float tiles are height maps (mm, relative to each tile's focal plane): each
// registered pair then measures the stage's z step too, from the overlap.

#include <functional>
#include <string>
#include <vector>

#include "artefacts/scan_observations.h"

namespace fvm::workflows {

// Throws InputError naming two --option paths that are the same file (however spelt).
void RefuseRepeatedFiles(const std::vector<std::string>& paths, const std::string& option);

// Throws InputError naming the layout and line: the same layout twice, a scan shorter than two tiles, encoder readings missing, or a step
// between consecutive tiles longer than the field of view (readings in pixels, or tiles that cannot overlap).
// `threads`: OpenCV's pool (0: all cores); `progress`: a line per scan on a terminal's stderr. `on_registered`,
// when given, sees each scan with its tiles while they are in memory (the field distortion's correspondences).
std::vector<artefacts::RegisteredScan> ReadAndRegisterScans(
    const std::vector<std::string>& layouts, double pixel_mm, int threads = 0, bool progress = false,
    const std::function<void(const artefacts::RegisteredScan&, const std::vector<imaging::TileImage>&)>& on_registered = {});

}  // namespace fvm::workflows
