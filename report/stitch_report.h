#pragma once
// The report of `fvm stitch --report DIR`: an HTML page with the summary, the tiles' positions with their standard
// uncertainties, every neighbour pair (accepted, overruled by the grid's loops, unresolved), the misclosure of every
// square of four tiles, and with --distortion the objective's field (its terms with u, the overlap correlation before
// and after); two SVG plots: the tiles and their pairs where they were placed, and the field's displacement across a
// tile. Units are the report's: pixels of the tiles (and um where the pixel size is known).

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fvm::report {

struct StitchReportData {
  std::string title;
  std::vector<std::pair<std::string, std::string>> summary;

  struct Table {
    std::string heading, note;  // note: a sentence under the heading, may be empty
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
  };
  std::vector<Table> tables;  // after the summary, in this order

  int width_px = 0, height_px = 0;  // of one tile
  struct Tile {
    std::string label;    // what the plot writes in it (the tile's number in the layout)
    double x_px, y_px;    // its top-left corner (x right, y down)
  };
  std::vector<Tile> tiles;
  enum class PairStatus { kAccepted, kOverruled, kUnresolved };
  struct Pair {
    int a, b;  // indices into tiles
    PairStatus status;
  };
  std::vector<Pair> pairs;

  // The field's displacement d(u) sampled across one tile (px at pixel u); empty without a field.
  struct Displacement {
    double x_px, y_px, dx_px, dy_px;
  };
  std::vector<Displacement> field;
  std::string field_caption;  // what the plot's subtitle says (largest displacement, where)
};

// Writes DIR/index.html, positions.svg and, with a field, field.svg, each atomically, the page last. Throws
// fvm::InputError naming DIR when it cannot be written, leaving nothing it created behind. Not thread-safe (PLplot).
void WriteStitchReport(const std::filesystem::path& dir, const StitchReportData& data);

}  // namespace fvm::report
