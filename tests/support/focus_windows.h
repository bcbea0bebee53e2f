#pragma once
// The adaptive mode's windows (imaging::kAdaptiveWindows, Gaussian-weighted) as the focus corrections receive them,
// without their per-pixel curves: for the tests of the corrections that read only each window's shape.

#include <vector>

#include "imaging/focus_stack_curves.h"
#include "imaging/focus_variation.h"

namespace fvm::imaging::testing {

inline std::vector<WindowCurves> AdaptiveWindows() {
  std::vector<WindowCurves> windows;
  for (int w : kAdaptiveWindows) {
    WindowCurves& c = windows.emplace_back();
    c.window = w, c.gaussian = true;
  }
  return windows;  // 3, 5 and 9 px
}

}  // namespace fvm::imaging::testing
