#pragma once
// How well placed tiles agree where they overlap: the normalised cross-correlation (NCC) of the pixel values two
// neighbours show in their common area, at given positions. No real tile set has a physical truth, but a wrong
// position puts different parts of the scene on top of each other, and the correlation of the overlap drops; so
// positions from two tools (or two methods) are compared by it, pair by pair (as MIST and Fiji judge theirs).
//
// The values as stored, with nothing filtered: the measure must not favour one registration's own prefilter. A
// sub-pixel offset resamples b bilinearly, which smooths b a little (the NCC of a noisy overlap at a fractional
// offset reads up to a few hundredths low); whole-pixel offsets read b's pixels as they are.
//
// Pixel frame as in tile_registration.h: x right, y down, positions are the tiles' top-left corners.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "imaging/grid_tile.h"
#include "imaging/io/tile_image.h"

namespace fvm::imaging {


struct OverlapCorrelation {
  double ncc = 0.0;  // in [-1, 1]; NaN when fewer than 64 valid pixels overlap or a side is constant
  int pixels = 0;    // valid pixels in both tiles over the overlap
};

// The overlap of a and b when b's top-left corner lies at `offset_px` in a's frame. NaN pixels are left out.
OverlapCorrelation OverlapNcc(const TileImage& a, const TileImage& b, const Eigen::Vector2d& offset_px);

// Right (col + 1) and lower (row + 1) neighbours of a grid, as RegisterTileGrid pairs them: (a, b) tile indices,
// in the order of the tiles, east before south; then, for a tile with no side neighbour (holes on every side), its
// diagonal neighbours (the earlier tile first), whose corners overlap.
std::vector<std::pair<int, int>> GridNeighbourPairs(const std::vector<GridTile>& tiles);

struct PairOverlapCorrelation {
  int a = 0, b = 0;
  OverlapCorrelation correlation;
};
// Every neighbour pair's overlap NCC at `positions_px` (one per image). Throws std::invalid_argument when the
// counts differ.
std::vector<PairOverlapCorrelation> NeighbourOverlapNcc(const std::vector<TileImage>& images,
                                                        const std::vector<GridTile>& tiles,
                                                        const std::vector<Eigen::Vector2d>& positions_px);

}  // namespace fvm::imaging
