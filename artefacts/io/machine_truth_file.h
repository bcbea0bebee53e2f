#pragma once
// The true geometric errors of a simulated machine tool as JSON: what `fvm simulate tracker --errors FILE.json`
// reads and what its truth.json holds (so a truth.json can be given back as --errors).
//
//   {
//     "workspace": {"min_mm": [0, 0, 0], "max_mm": [2500, 1500, 1200]},   optional; its min must match the machine's
//     "terms": {
//       "xTx": {"poly": [0, 1.2e-5, -3e-9, 1e-12],
//               "sine": {"amplitude": 0.002, "pitch_mm": 20, "phase_rad": 0.5}},
//       "EYX": {"poly": [0, 4e-6]},
//       "xWy": {"poly": [2e-5]}
//     }
//   }
//
// Each term, by [VDI 2617-3] name (xTx, yRz, xWy) or [ISO 230-1] alias (EXX, EC0Y), is
//   value(u) = poly[0] + poly[1] u + poly[2] u^2 + poly[3] u^3 + amplitude sin(2 pi u / pitch_mm + phase_rad)
// with u = q - min (mm) of the term's own axis: poly[i] in mm/mm^i for translation terms, rad/mm^i for rotations;
// amplitude in mm or rad. Up to 4 coefficients (a cubic); "sine" is optional. A squareness term is one angle:
// "poly": [rad], no sine. Terms not named are zero. Other keys at the top level are ignored (truth.json has many).

#include <filesystem>
#include <string>
#include <string_view>

#include "artefacts/machine_truth.h"

namespace fvm::artefacts {

// Throws InputError naming the file and the term on unreadable JSON, an unknown or repeated term (xTx and EXX
// are one term), an unknown key inside a term, a non-numeric, non-finite or missing value, more than 4
// coefficients, a non-positive pitch, a sine on a squareness term, a workspace whose min differs from ws.min,
// or a term larger than 10 mm (translation) or 10 mrad (rotation, squareness) somewhere on its travel (units?).
MachineTruth ReadMachineTruth(const std::filesystem::path& path, const Workspace& ws);
MachineTruth ParseMachineTruth(std::string_view json_text, const std::string& name, const Workspace& ws);

// The JSON text (the format above, every term with its VDI name) of a truth; ParseMachineTruth reads it back
// exactly (numbers are written as the shortest text of the same double).
std::string MachineTruthJson(const MachineTruth& truth);

}  // namespace fvm::artefacts
