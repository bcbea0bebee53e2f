#pragma once
// What the field-distortion jobs share about the correspondences of registered overlaps (`fvm calibrate --scan
// --distortion`, `fvm diagnose --layout/--scan`): how to match a narrow overlap band, and how much more the
// correspondences scatter over a quarter of an overlap than their points' own scatter allows.

#include <vector>

#include "imaging/field_distortion_fit.h"
#include "imaging/overlap_correspondences.h"

namespace fvm::workflows {

// The matching for a set whose narrowest registered overlap is `band_px` wide: the correspondences' windows (and the
// pyramid's reach) keep their centres half a window inside the band, so the default 15 px window leaves a 32 px band
// (128 px tiles at 25 %) two columns of points 8 px apart, whose windows the band's edges clip; the field's change
// across the band, all a chain of tiles shows of it, is then extrapolated over the whole tile (k1 found 1.68 for
// 2 px), and the clipped windows' bias, the same in every overlap, is a pattern a field fits (simulated scans without
// a field: a "field" of 57 px named). Narrow bands get a window of a quarter of the band (at least 7 px), one
// pyramid level, and a grid of a tenth of it (at least 2 px): eight columns over 22 px. Wide bands keep the options.
imaging::CorrespondenceOptions BandMatching(imaging::CorrespondenceOptions matching, double band_px);

// How much more the correspondences' errors scatter at the scale of a quarter of an overlap than their own scatter
// allows, about `fit`'s positions and field: each pair's inliers (within 3 point sigmas; pairs with fewer than
// `min_points` correspondences left out) split into four blocks along the band, each block's mean residual about the
// pair's (which the positions take up) against sigma^2 / n. The points of one overlap share errors at the windows'
// scale (the texture's): on scangen's scans (512 px, 20 %) the blocks scatter 1.4-1.7 times the points' sigma. At
// least 1; `dof`, when given, receives the blocks' degrees of freedom (2 x 3 a pair).
double OverlapBlockScatter(const std::vector<imaging::PairCorrespondences>& matched,
                           const imaging::FieldDistortionFit& fit, int min_points, int* dof = nullptr);

}  // namespace fvm::workflows
