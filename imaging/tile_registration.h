#pragma once
// Registration of overlapping tiles (FACTS.md section 1, "how stitching places tiles"): pairwise translations
// by phase correlation of the overlap, refined to sub-pixel, each with a quality; a weighted least-squares solve
// for all tile positions; tiles that no good pair connects to the first tile fall back to their stage positions,
// as the instrument does, and the registrations after them continue from there.
//
// Pixel frame: x to the right (+X), y down (-Y, row 0 of an image is its highest Y), positions are tiles' top-left
// corners in one mosaic frame.

#include <Eigen/Core>
#include <vector>

#include "imaging/tile_image.h"

namespace fvm::imaging {

struct RegistrationOptions {
  // Pairs whose quality (the normalised cross-correlation of the high-passed overlap once aligned) falls below
  // this are rejected. The same scene under 3 % noise and 30 % vignetting gives > 0.9; unrelated overlaps of a
  // few thousand pixels reach 0.3 at their best shift. The phase-correlation peak (`response`) is no test: it
  // ranged 0.04-0.9 on good pairs and up to 0.4 on unrelated ones in the tests.
  double min_quality = 0.5;
  // A shift farther from the nominal one than this fraction of the overlap's narrow side is rejected: the
  // correlation is periodic over the crop, so shifts near half of it are as likely wrapped as real.
  double max_correction = 0.35;
  // Correlate only the nominal overlap (true) or the whole frames (false: the baseline of the benchmark, slower
  // and noisier, since most of each frame has nothing to match).
  bool crop_to_overlap = true;
  // Refine the phase-correlation peak by Gauss-Newton on the overlap (Lanczos-4 resampling): the peak's centroid
  // alone is biased towards whole pixels by up to ~0.1 px.
  bool refine = true;
  // High-pass scale (px) applied before matching, so that uneven illumination and tilt do not correlate.
  double highpass_sigma_px = 8.0;
  // How far (px, standard deviation) a tile may be from its nominal position: the stage's error over the grid.
  // Along directions the images determine it moves nothing (their precision is ~0.01 px); along directions they
  // do not (a texture of parallel marks), it keeps the tile near its stage position.
  double stage_sigma_px = 2.0;
  // Register the pairs of a grid on OpenCV's thread pool (false: one thread, the benchmark's baseline). The
  // result is the same either way.
  bool parallel = true;
  void Check() const;  // throws std::invalid_argument for values outside their ranges
};

struct PairRegistration {
  int a = 0, b = 0;                                     // tile indices
  Eigen::Vector2d nominal_px = Eigen::Vector2d::Zero();  // b's top-left in a's frame, from the stage / grid
  Eigen::Vector2d offset_px = Eigen::Vector2d::Zero();   // measured, when accepted
  double response = 0.0;  // phase-correlation peak
  double quality = 0.0;   // normalised cross-correlation once aligned, in [-1, 1]
  // The offset's inverse covariance (px^-2), the pair's weight in the solve: from the texture the two tiles
  // share (the cross products of their gradients, which their independent noise leaves alone) and the residual
  // variance, with a floor of 0.005 px. A direction along which the texture does not change (machining marks, a
  // polished face) carries none: the overlap cannot tell a shift along it, and the stage decides it.
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
  bool accepted = false;
};

// Where b's top-left corner lies in a's pixel frame. Rejected (accepted = false) when the nominal overlap is
// smaller than 8 x 8 px, the shift is implausible, the quality is below the threshold, or the texture's gradient
// energy stands out of the noise's in no direction.
PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options);

struct TilePositions {
  std::vector<Eigen::Vector2d> positions_px;
  std::vector<bool> registered;  // false: no accepted pair links the tile to an earlier one: stage position
  std::vector<int> anchor;       // the tile whose stage position each tile's chain starts from
  // Standard uncertainty of each position relative to its anchor, per axis (px); 0 for an anchor. Near the stage
  // sigma along an axis that the images do not determine, where the tile stays near its stage position.
  std::vector<Eigen::Vector2d> sigma_px;
};

// Generalised least squares over accepted pairs, p_b - p_a = offset weighted by each pair's information, and the
// stage, p = nominal with standard deviation stage_sigma_px per axis. In every connected group of tiles the first
// (lowest index, i.e. earliest in the scan) keeps its nominal position exactly; a group of one tile is a tile
// without a good neighbour.
TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs, double stage_sigma_px = 2.0);

struct GridTile {
  int row = 0, col = 0;
  Eigen::Vector2d nominal_px = Eigen::Vector2d::Zero();
};

struct RegistrationResult {
  TilePositions positions;
  std::vector<PairRegistration> pairs;  // right and lower neighbours of every tile
};

// Registers each tile with its right (col + 1) and lower (row + 1) neighbour, in parallel, then solves. Tiles in
// scan order: index 0 is the anchor. images[i] belongs to tiles[i].
RegistrationResult RegisterTileGrid(const std::vector<TileImage>& images, const std::vector<GridTile>& tiles,
                                    const RegistrationOptions& options);

}  // namespace fvm::imaging
