#pragma once
// Tile layout files (docs/tutorials/stitching.md): CSV `file,row,col[,x,y[,z]]`, '#' comment lines allowed;
// file names relative to the layout's directory; row 0 is the highest Y and column 0 the lowest X (tile_plan.h); x, y
// the nominal stage position of the tile's centre in mm, optional. `fvm tiles plan` writes it, `fvm stitch` reads it.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"

namespace fvm::imaging {

// Bounds checked while reading, before anything is sized by them: a damaged layout (issue 19: a column index of
// 2147483647) fails naming its line instead of overflowing rows x cols. The published scans have 15 x 15 tiles.
inline constexpr int kMaxTilesPerAxis = 100000;
inline constexpr std::int64_t kMaxLayoutTiles = 1000000;  // rows x cols of the grid the tiles span

struct TileLayoutEntry {
  std::string file;  // as written in the layout
  int row = 0;
  int col = 0;
  std::optional<Eigen::Vector2d> stage_mm;  // tile centre
  int line = 0;                             // line of the layout file, for messages
  std::optional<double> stage_z_mm;         // the encoder's z there (calibration scans), optional
  // The tile's top-left corner in px (x right, y down) where a Fiji tile configuration places it
  // (fiji_tile_configuration.h): the nominal position the registration starts from. Initialised, so that the brace
  // lists that end before it stay free of -Wmissing-field-initializers.
  std::optional<Eigen::Vector2d> nominal_px = std::nullopt;
};

struct TileLayout {
  std::string source;
  std::vector<TileLayoutEntry> tiles;  // file order, which is the scan order
  int rows = 0, cols = 0;              // 1 + the largest row and column
};

// Throws InputError "FILE:LINE: problem; what to do" on a missing file, a header without file,row,col, a short or
// non-numeric row, an index outside 0 .. kMaxTilesPerAxis - 1, a grid of more than kMaxLayoutTiles, x without y,
// z without x and y, a (row, col) given twice, or no tiles. Columns other than file,row,col,x,y,z are ignored.
// A Fiji tile configuration (a `dim =` line first, whatever the extension) is read as one, its pitch found from the
// positions' gaps (imaging/io/fiji_tile_configuration.h).
TileLayout ReadTileLayout(const std::filesystem::path& path);

// Throws InputError when the grid or a tile is outside the bounds above, or when a layout of two tiles or more has no
// two neighbours (nothing to register), naming the first tile. Holes are allowed: a scanned region that is not a
// rectangle, or tiles left out (Fiji's and MIST's grids with missing tiles); each tile is registered with the
// neighbours the layout has; a tile with none beside it (TilesWithoutNeighbour) through the corners it shares with
// its diagonal ones (imaging::GridNeighbourPairs), or by the stage where none registers.
void CheckLayoutForStitching(const TileLayout& layout);

// The tiles (indices in layout order) that have no tile left, right, above or below them in the layout.
std::vector<size_t> TilesWithoutNeighbour(const TileLayout& layout);

// The tiles' images in layout order, file names relative to `dir` (an absolute name replaces it); `type`, when
// given, receives the first tile's pixel type. Throws InputError "LAYOUT:LINE: tile row R col C: ..." when one
// cannot be read (the first such tile in layout order), or is not the size of the first (one camera and lens make
// every tile of a layout). The tiles are decoded on `threads` threads at once (0: all cores).
std::vector<TileImage> ReadLayoutImages(const TileLayout& layout, const std::filesystem::path& dir,
                                        TilePixelType* type = nullptr, int threads = 0);

// The CSV text, 6 decimals of mm for x, y; file names quoted when they hold a comma or a quote.
std::string FormatTileLayout(const std::vector<TileLayoutEntry>& tiles);

}  // namespace fvm::imaging
