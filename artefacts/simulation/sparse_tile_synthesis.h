#pragma once
// Synthetic tiles that look like real microscope tiles of a sparse sample (issue 13): sparse bright blobs of varied
// size and brightness on a slowly varying background, 16-bit counts with shot noise, thin overlaps (5-8 %), and a
// stage whose every step is off by the same systematic error (a longer or shorter step, a sideways drift) plus a
// random repeatability per tile. Textured tiles (tile_synthesis.h) register anywhere in their overlap; these leave
// most of it blank, which is where registration by the nominal overlap alone fails.

#include <Eigen/Core>
#include <cstdint>

#include "artefacts/simulation/tile_synthesis.h"

namespace fvm::artefacts {

struct SparseTileOptions {
  int rows = 5, cols = 5;
  int width = 245, height = 183;  // px
  double overlap = 0.06;          // nominal fraction shared by neighbours
  // The stage's systematic error per step (px): a column step is the nominal one plus east_step_error (x along,
  // y across: the sideways drift), a row step the nominal one plus south_step_error (x across, y along).
  Eigen::Vector2d east_step_error_px{1.2, 4.0};
  Eigen::Vector2d south_step_error_px{-3.5, 1.5};
  // Random repeatability: every tile but the first departs from where the systematic steps put it by a normal
  // draw of this size per axis (px), independent from tile to tile (an encoder-controlled stage does not
  // accumulate it).
  double repeatability_px = 1.5;
  // Blobs: Gaussian spots with sigma uniform in [blob_sigma_min_px, blob_sigma_max_px] and peak heights
  // log-uniform in [blob_peak_min, blob_peak_max] counts above the background, at random places, this many per
  // 1000 px^2 of sample.
  double blobs_per_kpx2 = 1.2;
  double blob_sigma_min_px = 1.2, blob_sigma_max_px = 5.0;
  double blob_peak_min = 300.0, blob_peak_max = 6000.0;
  // Background: `background` counts, varying by +-background_variation of it over a few tiles (the sample's
  // reflectance), under 15 % vignetting of the lens.
  double background = 1500.0, background_variation = 0.3;
  double vignetting = 0.15;
  // Shot noise: a count is electrons_per_count photo-electrons, so a pixel of c counts scatters by
  // sqrt(c / electrons_per_count) counts; plus the sensor's read noise (counts, standard deviation).
  double electrons_per_count = 1.0, read_noise = 5.0;
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

// Tiles in scan order (column by column, top to bottom), nominal grid positions, and the true top-left corners
// (tile 0 at its nominal position), as SynthesizeTiles gives them; values are whole counts in [0, 65535] (16-bit).
// `scene` is left without texture: the blobs are not a TileScene.
SynthesizedTiles SynthesizeSparseTiles(const SparseTileOptions& options);

}  // namespace fvm::artefacts
