#pragma once
// Tile layout files (ARCHITECTURE.md section 3): CSV `file,row,col[,x,y]`, '#' comment lines allowed; file names
// relative to the layout's directory; row 0 is the highest Y and column 0 the lowest X (tile_plan.h); x, y the
// nominal stage position of the tile's centre in mm, optional. `fvm tiles plan` writes it, `fvm stitch` reads it.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fvm::imaging {

struct TileLayoutEntry {
  std::string file;  // as written in the layout
  int row = 0;
  int col = 0;
  std::optional<Eigen::Vector2d> stage_mm;  // tile centre
  int line = 0;                             // line of the layout file, for messages
};

struct TileLayout {
  std::string source;
  std::vector<TileLayoutEntry> tiles;  // file order, which is the scan order
  int rows = 0, cols = 0;              // 1 + the largest row and column
};

// Throws InputError "FILE:LINE: problem; what to do" on a missing file, a header without file,row,col, a short or
// non-numeric row, negative indices, x without y, a (row, col) given twice, or no tiles.
TileLayout ReadTileLayout(const std::filesystem::path& path);

// Throws InputError naming the first missing (row, col) when the tiles do not fill the rows x cols rectangle:
// registration needs every neighbour it is told about.
void CheckLayoutComplete(const TileLayout& layout);

// The CSV text, 6 decimals of mm for x, y.
std::string FormatTileLayout(const std::vector<TileLayoutEntry>& tiles);

}  // namespace fvm::imaging
