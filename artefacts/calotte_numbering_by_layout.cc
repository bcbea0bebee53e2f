#include "artefacts/calotte_numbering_by_layout.h"

#include <cmath>

#include "core/input_error.h"

namespace fvm::artefacts {

imaging::LayoutMatch NumberByLayout(imaging::CalotteDetection& detection, const Artefact& artefact,
                                    const imaging::LayoutMatchOptions& match, bool retry_turned) {
  std::vector<imaging::NominalCalotte> nominal;
  for (const Calotte& c : artefact.calottes) nominal.push_back({c.id, c.centre.head<2>()});
  std::vector<Eigen::Vector2d> found;
  for (const auto& c : detection.calottes) found.push_back(c.fit.centre_mm.head<2>());
  imaging::LayoutMatchOptions used = match;
  imaging::LayoutMatch layout;
  try {
    layout = imaging::MatchLayout(found, nominal, used);
  } catch (const InputError&) {
    if (!retry_turned) throw;
    used.expected_rotation_rad += M_PI / 4;
    try {
      layout = imaging::MatchLayout(found, nominal, used);
    } catch (const InputError&) {
      layout = imaging::MatchLayout(found, nominal, match);  // throws the first message
    }
  }
  imaging::NumberCalottes(detection, nominal, used);
  return layout;
}

}  // namespace fvm::artefacts
