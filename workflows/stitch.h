#pragma once
// Overlapping tiles registered into one frame (`fvm stitch`): nominal positions from the stage (when the layout
// has them and the pixel size converts them) or from the grid and the overlap, every neighbour pair registered,
// the positions solved, and each pair judged by its overlap correlation at the positions found.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/io/tile_layout.h"
#include "imaging/overlap_correlation.h"
#include "imaging/tile_registration.h"

namespace fvm::workflows {

struct StitchOptions {
  double overlap = 0.2;         // nominal overlap, fraction of a tile
  double pixel_mm = 0.0;        // > 0: the layout's stage positions (mm) give the nominal positions
  imaging::RegistrationOptions registration;
  int threads = 0;              // OpenCV's pool; 0: all cores
  // Throws InputError naming the option as fvm stitch spells it (--overlap, --pixel-mm, --min-quality,
  // --stage-sigma-px, --threads).
  void Check() const;
};

// The nominal grid, the first tile of the layout at the origin (image y runs down = -Y). `from_stage`: whether the
// stage positions gave it.
std::vector<imaging::GridTile> NominalGrid(const imaging::TileLayout& layout, int width_px, int height_px,
                                           const StitchOptions& options, bool* from_stage);
// The pairs imaging::RegisterTileGrid registers (right and lower neighbours, and the corners of a tile without
// either): the total of a progress count.
int CountGridPairs(const std::vector<imaging::GridTile>& grid);

struct StitchResult {
  std::vector<imaging::GridTile> grid;
  bool from_stage = false;
  // The stage frame (+Y up) of the first tile's centre when the layout has stage positions, else 0, 0: the origin
  // of positions in mm and of a height-map mosaic.
  Eigen::Vector2d origin_mm = Eigen::Vector2d::Zero();
  imaging::RegistrationResult registration;
  // Each neighbour pair's overlap correlation at the positions found (the measure without a truth), their mean.
  std::vector<imaging::PairOverlapCorrelation> overlap_ncc;
  double mean_overlap_ncc = NAN;
  int ncc_pairs = 0, accepted = 0, ambiguous = 0;
  std::vector<std::string> at_stage_position;   // tiles no good pair links to an earlier one (registered 0)
  std::vector<std::string> stage_along_one_axis;  // linked to the first by pairs fixing one direction (registered 0)
  // Tiles the layout gives no neighbour beside them (holes on every side): registered through the corners they share
  // with their diagonal neighbours, or placed by the stage (at_stage_position) where none registers. "FILE (row R
  // col C)".
  std::vector<std::string> without_neighbour;
  // Pairs the loops of the grid overruled ("a - b: why, and what was done"), in the order they were.
  std::vector<std::string> overruled;
  // Pairs that place nothing (rejected or dropped); a quarter or more of them is a run to distrust, said aloud.
  int unresolved = 0;
  bool mostly_unresolved = false;
  std::string UnresolvedWarning() const;  // empty unless mostly_unresolved
};

// StitchResult's account of `s.registration`: its accepted and ambiguous pairs, the pairs its loops overruled, the
// unresolved ones, and the tiles it leaves at their stage positions or places along one axis (named from `files`, the
// layout's tiles in its order). What it had said before is replaced; the grid and the overlap correlation stay.
void DescribeRegistration(StitchResult& s, const std::vector<std::string>& files);

// `images[i]` is the layout's tile i. `on_pair` is called as each pair is registered (progress).
StitchResult StitchTiles(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                         const StitchOptions& options, const std::function<void(int done, int total)>& on_pair = {});

}  // namespace fvm::workflows
