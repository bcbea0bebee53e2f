#pragma once
// Fiji's tile configuration (`TileConfiguration.txt`, `TileConfiguration.registered.txt`) as a tile layout, and
// positions written in its registered form, for users of Fiji's Grid/Collection stitching [Preibisch 2009] and MIST.
//
//   # Define the number of dimensions we are working on
//   dim = 2
//   # Define the image coordinates
//   tile_001.tif; ; (0.0, 0.0)
//   tile_002.tif; ; (921.5, -0.25)
//
// '#' comment and blank lines anywhere; `dim = 2` (or 3: `(x, y, z)`, every tile in one plane) before the first tile;
// each tile `name; series; (x, y)`: the image file relative to the configuration's directory, an empty series (one
// image a file), the position of the tile's top-left corner in pixels (x right, y down), in any order, negative or in
// exponent form (Java's 1.5E-4). The rows and columns are the positions clustered with the pitch (tile_layout.h:
// row 0 the lowest y, column 0 the lowest x); the positions themselves are kept as the nominal ones the registration
// starts from (TileLayoutEntry::nominal_px).

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imaging/io/tile_layout.h"

namespace fvm::imaging {

struct FijiTile {
  std::string file;
  Eigen::Vector2d position_px = Eigen::Vector2d::Zero();  // top-left corner, x right, y down
  int line = 0;
};

struct FijiTileConfiguration {
  std::string source;
  int dim = 2;
  std::vector<FijiTile> tiles;  // file order
};

// Whether the file's first line that is neither blank nor a '#' comment is `dim = ...`: a Fiji tile configuration,
// whatever its extension. False when the file cannot be read (its reader then says why).
bool IsFijiTileConfiguration(const std::filesystem::path& path);

// Throws InputError "FILE:LINE: problem; what to do" on a missing file, a tile before `dim =`, a dimension other than
// 2 or 3, a line that is not `name; ; (x, y)`, a series number (multi-series files), a coordinate that is not a
// finite number or lies beyond 1e9 px, a z that differs from the first tile's, a tile named twice, or no tiles.
FijiTileConfiguration ReadFijiTileConfiguration(const std::filesystem::path& path);
FijiTileConfiguration ParseFijiTileConfiguration(std::string_view text, const std::string& source);

// The pitch (x, y; px) between neighbouring tiles' positions found from the gaps between the sorted coordinates: the
// median of the gaps wider than a sixth of the widest (narrower ones are the scatter of one column or row). An axis
// with one column (row) takes the other's pitch.
Eigen::Vector2d PitchFromGaps(const FijiTileConfiguration& config);

// The configuration as a layout: along each axis the coordinates closer than a third of `pitch_px` form one column
// (row); neighbouring columns are as many pitches apart as their distance rounds to, counted from the first tile's,
// so that a stage's scale error does not add up along the grid. Missing tiles leave holes (CheckLayoutForStitching
// decides). Throws InputError "FILE:LINE: tile NAME ..." for a tile on no node of the grid (a third of a pitch or
// more from every one) and for two tiles on one node. `pitch_px` defaults to PitchFromGaps.
TileLayout FijiTileLayout(const FijiTileConfiguration& config, std::optional<Eigen::Vector2d> pitch_px = {});

// The registered form Fiji writes and reads: a comment, `dim = 2`, one line `name; ; (x, y)` a tile with its
// position in px (4 decimals, as the positions CSV). Throws InputError for a name Fiji cannot read back (holding
// ';', a line break, or blank).
std::string FormatFijiTileConfiguration(const std::vector<std::string>& files,
                                        const std::vector<Eigen::Vector2d>& positions_px);

}  // namespace fvm::imaging
