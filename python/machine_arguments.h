#pragma once
// What the machine-tool functions of the module share (machine.cc, testpiece.cc, tracker.cc): readings given as a
// CSV path or as arrays, tool offsets, a held pose, and fvm verify's options built from their keywords.

#include <optional>
#include <string>

#include "artefacts/io/tracker_readings.h"
#include "python/bindings.h"
#include "workflows/machine_problem.h"
#include "workflows/summary.h"

namespace fvm::python {

// A CSV path, or {"nominal": N x 3, "measured": N x 3 (tracker frame, Cartesian, mm), optional "ids" and "tool"
// (1, 2, ... into the tool offsets), "approach" (+x, ...)}.
artefacts::TrackerReadings ReadingsFrom(const py::object& arg, const std::string& what);

// The shared keywords (fvm verify's DATA, --tool, --chain, --basis, --validate, --pose, --machine, --tracker,
// --unweighted, --max-error-mm, --threads); `defaults` gives what a keyword left out means.
struct MachineKeywords {
  py::object readings, tool, validate, pose;
  std::string chain, basis, tracker;
  bool unweighted = false;
  double max_error_mm = 0;
  int threads = 0;
  py::object machine = py::none();  // the axes' travel X0, Y0, Z0, X1, Y1, Z1 (mm), as --machine gives it
};
workflows::MachineProblemOptions MachineOptionsFrom(const MachineKeywords& k, workflows::MachineProblemOptions defaults);
// The problem read (files) or made (arrays) without the GIL; refusals as the command line's.
workflows::MachineProblem MachineProblemFrom(const MachineKeywords& k, const workflows::MachineProblemOptions& options);

}  // namespace fvm::python
