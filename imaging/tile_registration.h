#pragma once
// Registration of overlapping tiles ([Pérez 2019] section 1.2: how stitching places tiles): pairwise translations
// (tile_pair_registration.h), each with its uncertainty; a generalised least-squares solve for all tile positions;
// tiles that no good pair connects to the first tile fall back to their stage positions, as the instrument does,
// and the registrations after them continue from there.
//
// Pixel frame: x to the right (+X), y down (-Y, row 0 of an image is its highest Y), positions are tiles' top-left
// corners in one mosaic frame.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/grid_tile.h"
#include "imaging/loop_misclosure.h"
#include "imaging/tile_grid_steps.h"
#include "imaging/tile_pair_registration.h"

namespace fvm::imaging {
struct TilePositions {
  std::vector<Eigen::Vector2d> positions_px;
  std::vector<bool> registered;  // false: no accepted pair links the tile to an earlier one: stage position
  std::vector<int> anchor;       // the tile whose stage position each tile's chain starts from
  // Standard uncertainty of each position relative to the first tile, per axis (px): 0 for the first tile; a tile
  // no pair links to it carries the stage's uncertainty (its chain's anchor's, added to its own relative to that
  // anchor). Near the stage sigma along an axis that the images do not determine.
  std::vector<Eigen::Vector2d> sigma_px;
};

// Each tile's group of tiles joined by accepted pairs, named by its earliest tile (union-find).
std::vector<int> PairGroups(int tiles, const std::vector<PairRegistration>& pairs);

// Generalised least squares over accepted pairs, p_b - p_a = offset weighted by each pair's information, and the
// stage, p = nominal with standard deviation stage_sigma_px per axis. In every connected group of tiles the first
// (lowest index, i.e. earliest in the scan) keeps its nominal position exactly; a group of one tile is a tile
// without a good neighbour.
// `unregistered_sigma_px`: the standard uncertainty of a chain's anchor other than the first tile, per axis
// (negative: stage_sigma_px).
TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs, double stage_sigma_px = 2.0,
                                 const Eigen::Vector2d& unregistered_sigma_px = Eigen::Vector2d::Constant(-1.0));

struct RegistrationResult {
  TilePositions positions;
  std::vector<PairRegistration> pairs;  // right and lower neighbours of every tile
  // The stage as the accepted pairs show it (none estimated when too few registered), and what the solve took
  // for each tile's stage position and its standard deviation: the nominal corrected by the model.
  TileGridSteps stage;
  std::vector<Eigen::Vector2d> stage_positions_px;
  double stage_sigma_px = 0.0;
  // The stage's error shared along rows and columns, as the final solve took it (SolveGridPositions).
  StageAxesPrior stage_axes;
  int pairs_searched_again = 0;  // pairs the model's window searched a second time
  // The pairs the loops of the grid overruled (loop_misclosure.h), and how far the loops' misclosures exceed what
  // the pairs claim (the pairs' information is scaled by it before the solve).
  LoopCheck loops;
  // Pairs that place nothing (rejected, refused for a step along their scan axis far from the grid's, or dropped by
  // the loops). When a quarter or more of the pairs are, the
  // positions rest on the stage as much as on the images: the run says so.
  int pairs_unresolved = 0;
  bool MostlyUnresolved() const { return !pairs.empty() && 4 * pairs_unresolved >= static_cast<int>(pairs.size()); }
};

// Registers each tile with its right (col + 1) and lower (row + 1) neighbour, in parallel, within
// options.search_fraction of the nominal offsets. From the accepted pairs it estimates the stage model; pairs that
// failed, or that disagree with the model by more than its tolerance, are searched again within that tolerance of
// the model's offset; what registers stands (the first match where the search found nothing), and pairs still
// failing are searched over the whole plausible range. A pair whose step along its scan axis lies farther from the
// grid's median step than the first window is refused (a neighbouring trace of a line pattern). Then the loops of the grid judge every pair
// (loop_misclosure.h: overruled pairs searched again where the loops put them or dropped, rejected ones searched
// there, the weights scaled by the loops' Birge ratio), and it solves with the model's positions as the stage prior,
// its sigma the placed tiles' spread about them (the model's repeatability at least). Tiles in scan order: index 0 is the anchor. images[i] belongs to tiles[i]. `on_pair_registered(done, total)`, when
// given, is called after each pair, from the pool's threads at once: it must be thread-safe.
RegistrationResult RegisterTileGrid(const std::vector<TileImage>& images, const std::vector<GridTile>& tiles,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered = {});

// A scan path: tiles in scan order, each overlapping the one before it (a row, a column or a diagonal of a
// calibration scan, fvm tiles plan --calibration-scan). Each consecutive pair is registered as a grid's pairs are
// (nominal overlap first, thin overlaps and failures searched widened within options.search_fraction); positions
// are chained from tile 0 (SolveTilePositions with options.stage_sigma_px). A chain has no rows and columns to
// learn a stage model from, and needs none: the nominal offsets come from the encoders, a pixel or two from true.
struct ChainRegistration {
  std::vector<PairRegistration> pairs;  // (k, k + 1) for k = 0 .. n - 2
  TilePositions positions;
  int pairs_searched_again = 0;
};
ChainRegistration RegisterTileChain(const std::vector<TileImage>& images, const std::vector<Eigen::Vector2d>& nominal_px,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered = {});

// Threads of OpenCV's pool, which registration, mosaics and focus stacks run on; 0: all cores. Process-wide.
void SetImagingThreads(int threads);

}  // namespace fvm::imaging
