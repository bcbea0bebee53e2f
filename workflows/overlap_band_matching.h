#pragma once
// How the field-distortion jobs (`fvm calibrate --scan --distortion`, `fvm diagnose --layout/--scan`) gather the
// correspondences of registered overlaps for one field fit, narrow overlap bands included. (How much more they
// scatter over a quarter of an overlap than their points allow is the field fit's own:
// FieldDistortionFit::block_scatter_factor.)

#include <Eigen/Core>
#include <string>
#include <vector>

#include "imaging/overlap_correspondences.h"
#include "imaging/tile_pair_registration.h"
#include "imaging/tile_registration.h"

namespace fvm::workflows {

// The matching for a set whose narrowest registered overlap is `band_px` wide: the correspondences' windows (and the
// pyramid's reach) keep their centres half a window inside the band, so the default 15 px window leaves a 32 px band
// (128 px tiles at 25 %) two columns of points 8 px apart, whose windows the band's edges clip; the field's change
// across the band, all a chain of tiles shows of it, is then extrapolated over the whole tile (k1 found 1.68 for
// 2 px), and the clipped windows' bias, the same in every overlap, is a pattern a field fits (simulated scans without
// a field: a "field" of 57 px named). Narrow bands get a window of a quarter of the band (at least 7 px), one
// pyramid level, and a grid of a tenth of it (at least 2 px): eight columns over 22 px. Wide bands keep the options.
imaging::CorrespondenceOptions BandMatching(imaging::CorrespondenceOptions matching, double band_px);

// Registered sets of tiles (a grid, or each calibration scan in turn) in one index space, as FitFieldDistortion
// takes them: every accepted pair's correspondences, the tiles' rigid positions, and the tiles that hold: the first
// of each group of tiles the accepted pairs join (not every tile the rigid solve calls unregistered: one placed
// through pairs that fix one direction is, and held at its rigid position it would pull the field).
struct RegisteredOverlapPoints {
  std::vector<imaging::PairCorrespondences> matched;
  std::vector<Eigen::Vector2d> initial;
  std::vector<bool> fixed;
  int width = 0, height = 0;  // of every tile: one field is one objective and one camera
};

// Appends one registered set: its accepted pairs' overlaps matched from `guess` with the matching of the set's
// narrowest band. Returns, for each correspondence set it appended to `points.matched`, the index of its pair in
// `pairs`. Throws InputError naming `set` (e.g. "--distortion: scan row") when its tiles' size differs from the sets'
// before.
std::vector<size_t> AppendRegisteredSet(const std::vector<imaging::TileImage>& images,
                                        const std::vector<imaging::PairRegistration>& pairs,
                                        const imaging::TilePositions& positions, const imaging::FieldDistortion& guess,
                                        const imaging::CorrespondenceOptions& matching, const std::string& set,
                                        RegisteredOverlapPoints& points);

}  // namespace fvm::workflows
