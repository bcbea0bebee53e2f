#pragma once
// Numbers found calottes as the artefact numbers them, by matching their positions to the nominal layout.
//
// Hypotheses come from pairing a found calotte and one of its nearest neighbours with a nominal calotte and one
// of its nearest neighbours: each pairing fixes a similarity transform (rotation, scale, translation). The
// hypothesis that brings the most found calottes within the tolerance of a nominal one wins; the transform is
// then refined by least squares [Umeyama 1991] over the matched pairs. A symmetric layout fits in several ways
// (the 6 x 6 grid in four, the bar in two): the one whose rotation is nearest the expected one wins, as the
// artefact is placed roughly as drawn (calotte 1 at lowest x, highest y: the first tile, [Pérez thesis] 5.7.2). When
// two fits are equally near (a bar turned by 90 degrees), or a partial view fits in several places, numbering would
// be a guess: it throws and says what to give.

#include <Eigen/Core>
#include <vector>

#include "imaging/calotte_detection.h"

namespace fvm::imaging {

struct NominalCalotte {
  int id = 0;
  Eigen::Vector2d xy_mm = Eigen::Vector2d::Zero();  // in the artefact's frame
};

struct LayoutMatchOptions {
  double expected_rotation_rad = 0.0;  // the artefact's frame turned by this in the map
  // A found calotte matches a nominal one within this distance after the transform; 0: a quarter of the
  // smallest nominal spacing.
  double tolerance_mm = 0.0;
  double max_scale_error = 0.05;         // |scale - 1| beyond this is not the artefact (or not in mm)
  double ambiguity_margin_rad = 0.1745;  // 10 degrees: rivals nearer than this to the expected rotation are a tie
  void Check() const;                    // throws std::invalid_argument
};

struct LayoutMatch {
  std::vector<int> ids;  // per found calotte: its nominal id, 0 when it matches none
  int matched = 0;
  // map = scale R(rotation) nominal + translation
  double rotation_rad = 0.0;
  double scale = 1.0;
  Eigen::Vector2d translation_mm = Eigen::Vector2d::Zero();
  double rms_mm = 0.0;  // of the matched calottes about the transformed nominal layout
};

// Throws InputError when fewer than two calottes were found (and the layout has more than one), nothing fits,
// or the numbering is ambiguous (the message names the rival rotations).
LayoutMatch MatchLayout(const std::vector<Eigen::Vector2d>& found, const std::vector<NominalCalotte>& nominal,
                        const LayoutMatchOptions& options = {});

// Gives every detected calotte its nominal id (by the centres' x, y) and lists them by id; a dimple that matches
// no nominal calotte moves to the rejected regions. Throws as MatchLayout.
void NumberCalottes(CalotteDetection& detection, const std::vector<NominalCalotte>& nominal,
                    const LayoutMatchOptions& options = {});

}  // namespace fvm::imaging
