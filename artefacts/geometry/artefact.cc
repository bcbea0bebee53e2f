#include "artefacts/geometry/artefact.h"

#include "core/input_error.h"

namespace fvm::artefacts {

Artefact CalotteBar17() {
  Artefact bar{"bar17", {}};
  for (int i = 0; i < 17; ++i) bar.calottes.push_back(Calotte{i + 1, Eigen::Vector3d(10.0 * i, 0.0, 0.0), 1.0});
  return bar;
}

Artefact CalotteGrid6x6() {
  Artefact grid{"grid6x6", {}};
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 6; ++col) {
      grid.calottes.push_back(Calotte{row * 6 + col + 1, Eigen::Vector3d(4.0 * col, -4.0 * row, 0.0), 0.25});
    }
  }
  return grid;
}

Artefact KnownArtefact(const std::string& name) {
  if (name == "grid6x6") return CalotteGrid6x6();
  if (name == "bar17") return CalotteBar17();
  throw InputError("--artefact '" + name + "': not an artefact fvm knows; use grid6x6 or bar17");
}

}  // namespace fvm::artefacts
