#pragma once
// The published stitching strategies (artefacts/stitching_strategy.h) played on images: every tile of the row is
// rendered where the stage really puts it, neighbouring tiles are registered (imaging/tile_registration.h) with
// the encoder readings as nominal positions, each strategy's tiles are solved as fvm stitch solves them (a tile
// that no accepted pair links to an earlier one keeps its encoder position), and the two calottes are found and
// fitted in height maps of the end tiles (imaging/calotte_detection.h). What the coordinate model assumes, that
// registration is exact and only missing tiles fall back to the encoders, is here measured: registration noise
// and rejected pairs enter the distance.
//
// Simplifications, each below a tenth of a pixel over a tile: the stage's yaw and squareness turn a tile by
// ~1e-4 rad, which is not rendered; the heights of a registered tile follow its anchor's encoder, as in the
// coordinate model (the images register x and y only).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "artefacts/simulation/stitching_strategy.h"
#include "artefacts/simulation/tile_synthesis.h"
#include "imaging/tile_registration.h"
#include "stage/parameter_layout.h"

namespace fvm::artefacts {

struct RenderedStrategyOptions {
  StrategyOptions geometry;
  int tile_px = 512;  // pixels across the field of view (square tiles)
  TileCameraOptions camera;
  imaging::RegistrationOptions registration;
  double calotte_radius_mm = 0.25;  // the 6 x 6 grid's ([Pérez 2019] 1.2)
  double height_noise_mm = 1e-4;    // the 10x lens' vertical resolution ([Pérez thesis] Table 5.2)
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct RenderedStrategyResult {
  StrategyResult result;       // from the images: tiles solved by registration, calottes fitted
  StrategyResult coordinates;  // the coordinate model (stitching_strategy.h) for the same case and row
  int pairs = 0;                     // neighbour pairs the case has (both tiles taken)
  int accepted_pairs = 0;
};

struct RenderedStrategies {
  double pixel_mm = 0.0;
  int row_tiles = 0;
  double pair_rms_px = 0.0;  // registration error of the accepted neighbour pairs against the rendered truth
  int rejected_pairs = 0;    // of the row's n - 1 neighbour pairs
  std::vector<RenderedStrategyResult> cases;
  // The rendered row, for fvm stitch: the images, in scan order, and where the encoders put each tile's centre.
  std::vector<imaging::TileImage> images;
  std::vector<Eigen::Vector2d> encoder_centres_mm;
};

// `first` and `last` are the calottes' true positions (mm), the stage error model F of `layout` with `values`.
// Throws std::invalid_argument for inconsistent options, std::runtime_error when a calotte is not found in its
// tile.
RenderedStrategies SimulateRenderedStrategies(const stage::ParameterLayout& layout, const std::vector<double>& values,
                                              const Eigen::Vector3d& first, const Eigen::Vector3d& last,
                                              const RenderedStrategyOptions& options = {});

}  // namespace fvm::artefacts
