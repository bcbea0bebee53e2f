#pragma once
// The calottes of an artefact on one surface (`fvm fit FILE`): searched in a height map (a file's, or an
// organised cloud's grid) or an unorganised 2.5D cloud, a sphere fitted to each, and, when the artefact is named,
// numbered as it numbers them.

#include <optional>
#include <string>

#include "artefacts/geometry/artefact.h"
#include "imaging/calotte_detection.h"
#include "imaging/calotte_numbering.h"
#include "imaging/height_map.h"
#include "imaging/io/surface_file.h"

namespace fvm::workflows {

struct FindCalottesOptions {
  std::optional<artefacts::Artefact> artefact;  // numbers the calottes (artefacts::KnownArtefact); none: no numbering
  double radius_mm = 0.0;               // > 0: the spheres' radius held at this
  std::optional<double> rotation_deg;   // how the artefact is expected to lie (numbering)
  double min_diameter_mm = 0.0, max_diameter_mm = 0.0;  // > 0: instead of the artefact's (or the defaults)
  double min_depth_mm = 0.0;
  imaging::SphereResidual residual = imaging::SphereResidual::kHeight;
};

struct FoundCalottes {
  imaging::CalotteDetection detection;
  std::optional<artefacts::Artefact> artefact;
  std::optional<imaging::LayoutMatch> layout;  // with an artefact
  std::optional<imaging::HeightMap> map;       // the map searched; none for an unorganised cloud
  std::string method = "height map";           // how the calottes were found
};

// `name` (the file) prefixes every refusal: no calotte found (naming the depressions rejected), a layout that does
// not match, a diameter window upside down.
FoundCalottes FindCalottes(imaging::Surface surface, const FindCalottesOptions& options, const std::string& name);

}  // namespace fvm::workflows
