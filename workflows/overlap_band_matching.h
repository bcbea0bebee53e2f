#pragma once
// How the field-distortion jobs (`fvm calibrate --scan --distortion`, `fvm diagnose --layout/--scan`) match the
// correspondences of a narrow overlap band. (How much more they scatter over a quarter of an overlap than their
// points allow is the field fit's own: FieldDistortionFit::block_scatter_factor.)

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

}  // namespace fvm::workflows
