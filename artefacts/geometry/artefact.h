#pragma once
// Nominal geometry of the calotte artefacts of [Pérez 2019] (section 1.2; the bar: section 2.2), in the artefact's own
// frame (mm): x along the rows, y across, z = 0 on the top face; calottes numbered as the artefact is.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace fvm::artefacts {

struct Calotte {
  int id = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // mm
  double radius_mm = 0.0;
};

struct Artefact {
  std::string name;
  std::vector<Calotte> calottes;
};

// Aluminium bar 180 x 18 x 18 mm, 17 calottes of 2 mm diameter at 10 mm pitch, ids 1..17 along +x.
Artefact CalotteBar17();
// Steel plate 28 x 28 x 5 mm, 6 x 6 calottes of 0.5 mm diameter at 4 mm pitch, ids 1..36 left to right,
// top to bottom (1 at top left, 6 top right, 31 bottom left).
Artefact CalotteGrid6x6();

// The artefact of that name: "grid6x6" or "bar17". Throws InputError naming the known ones otherwise.
Artefact KnownArtefact(const std::string& name);

}  // namespace fvm::artefacts
