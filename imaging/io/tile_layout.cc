#include "imaging/io/tile_layout.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <exception>
#include <utility>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/csv.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/fiji_tile_configuration.h"
#include "imaging/io/image_codec.h"
#include "imaging/io/tile_image.h"

namespace fvm::imaging {

TileLayout ReadTileLayout(const std::filesystem::path& path) {
  if (IsFijiTileConfiguration(path)) return FijiTileLayout(ReadFijiTileConfiguration(path));
  CsvOptions options;
  options.expected_header = "file,row,col[,x,y[,z]]";
  options.max_rows = static_cast<std::size_t>(kMaxLayoutTiles);
  const CsvTable table = ReadCsv(path, options);
  const int file = table.Require("file"), row = table.Require("row"), col = table.Require("col");
  const int x = table.Optional("x"), y = table.Optional("y"), z = table.Optional("z");
  if ((x < 0) != (y < 0)) {
    throw InputError(table.name() + ":" + std::to_string(table.header_line()) +
                     ": the header has only one of x, y; give both or neither");
  }
  if (z >= 0 && x < 0) {
    throw InputError(table.name() + ":" + std::to_string(table.header_line()) + ": the header has z without x, y; give all three");
  }
  // Encoder readings within 100 m of the origin, as the options' coordinates (fvm/option_ranges.h): beyond, a
  // value is a unit slip or a broken export, and its squares overflow in the fit (a y of 1e308 reached the
  // rigid-motion QR of fvm calibrate --scan as -inf, issue 44).
  constexpr double kMaxStageMm = 1e5;
  const auto stage = [&](const CsvRow& record, int column) {
    const double v = table.Double(record, column);
    if (std::abs(v) > kMaxStageMm) {
      table.Fail(record, "column '" + table.header()[static_cast<std::size_t>(column)] + "' = " + FormatShortest(v) +
                             " mm is beyond 100 m: give the stage's encoder reading in mm");
    }
    return v;
  };
  TileLayout layout;
  layout.source = table.name();
  std::map<std::pair<int, int>, int> seen;
  for (const CsvRow& record : table.rows()) {
    TileLayoutEntry entry;
    entry.line = record.line;
    entry.file = table.Text(record, file);
    if (entry.file.empty()) table.Fail(record, "empty file name; name the tile's image file");
    entry.row = static_cast<int>(table.Int(record, row, 0, kMaxTilesPerAxis - 1));
    entry.col = static_cast<int>(table.Int(record, col, 0, kMaxTilesPerAxis - 1));
    if (x >= 0) entry.stage_mm = Eigen::Vector2d(stage(record, x), stage(record, y));
    if (z >= 0) entry.stage_z_mm = stage(record, z);
    const auto [it, fresh] = seen.emplace(std::make_pair(entry.row, entry.col), record.line);
    if (!fresh) {
      table.Fail(record, "tile row " + std::to_string(entry.row) + " col " + std::to_string(entry.col) +
                           " is given twice (first on line " + std::to_string(it->second) + "); give each tile once");
    }
    const int rows = std::max(layout.rows, entry.row + 1), cols = std::max(layout.cols, entry.col + 1);
    if (std::int64_t{rows} * cols > kMaxLayoutTiles) {
      table.Fail(record, "tile row " + std::to_string(entry.row) + " col " + std::to_string(entry.col) +
                           " makes the grid " + std::to_string(rows) + " x " + std::to_string(cols) +
                           ", more than the " + std::to_string(kMaxLayoutTiles) +
                           " tiles a layout may span; check the row and col columns");
    }
    layout.rows = rows;
    layout.cols = cols;
    layout.tiles.push_back(std::move(entry));
  }
  if (layout.tiles.empty()) throw InputError(table.name() + ": no tiles after the header; give one row per tile");
  return layout;
}

void CheckLayoutForStitching(const TileLayout& layout) {
  // A layout built in code has not passed the reader's bounds: check them.
  if (layout.rows < 0 || layout.cols < 0 || layout.rows > kMaxTilesPerAxis || layout.cols > kMaxTilesPerAxis ||
      std::int64_t{layout.rows} * layout.cols > kMaxLayoutTiles) {
    throw InputError(layout.source + ": a grid of " + std::to_string(layout.rows) + " x " +
                     std::to_string(layout.cols) + " tiles is outside the bounds of a layout; check the rows and cols");
  }
  for (const auto& tile : layout.tiles) {
    if (tile.row < 0 || tile.col < 0 || tile.row >= layout.rows || tile.col >= layout.cols) {
      throw InputError(layout.source + ":" + std::to_string(tile.line) + ": tile row " + std::to_string(tile.row) +
                       " col " + std::to_string(tile.col) + " is outside the " + std::to_string(layout.rows) + " x " +
                       std::to_string(layout.cols) + " grid; check the layout");
    }
  }
  // Holes are allowed (a region that is not a rectangle, a tile left out): the tiles beside them are registered with
  // the neighbours they have. A layout in which no two tiles are neighbours has nothing to register.
  if (layout.tiles.size() > 1 && TilesWithoutNeighbour(layout).size() == layout.tiles.size()) {
    const TileLayoutEntry& first = layout.tiles.front();
    throw InputError(layout.source + ":" + std::to_string(first.line) + ": no two tiles are neighbours (tile " +
                     first.file + " at row " + std::to_string(first.row) + " col " + std::to_string(first.col) +
                     " has none, nor has any other): stitching registers neighbouring tiles; check the row and col "
                     "columns");
  }
}

std::vector<size_t> TilesWithoutNeighbour(const TileLayout& layout) {
  std::set<std::pair<int, int>> at;
  for (const auto& tile : layout.tiles) at.insert({tile.row, tile.col});
  std::vector<size_t> alone;
  for (size_t i = 0; i < layout.tiles.size(); ++i) {
    const int r = layout.tiles[i].row, c = layout.tiles[i].col;
    if (!at.count({r, c - 1}) && !at.count({r, c + 1}) && !at.count({r - 1, c}) && !at.count({r + 1, c})) {
      alone.push_back(i);
    }
  }
  return alone;
}

std::vector<TileImage> ReadLayoutImages(const TileLayout& layout, const std::filesystem::path& dir, TilePixelType* type,
                                        int threads) {
  const auto where = [&](const TileLayoutEntry& tile) {
    return layout.source + ":" + std::to_string(tile.line) + ": tile row " + std::to_string(tile.row) + " col " +
           std::to_string(tile.col) + ": ";
  };
  const size_t n = layout.tiles.size();
  std::vector<TileImage> images(n);
  std::vector<TilePixelType> types(n, TilePixelType::kFloat);
  std::vector<std::exception_ptr> failures(n);
  // Decoded side by side (a grid of megapixel colour tiles spent as long decoding as registering on one thread);
  // the codec loaded first, once. What failed is reported for the first failing tile in layout order, as when
  // they were read in turn.
  if (n > 0) LoadImageCodec("reading " + (dir / layout.tiles.front().file).string());
  const auto read = [&](size_t k) {
    try {
      images[k] = ReadTileImage(dir / layout.tiles[k].file, &types[k]);
    } catch (...) {
      failures[k] = std::current_exception();
    }
  };
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(size_t{0}, n, read); });
  for (size_t k = 0; k < n; ++k) {
    const TileLayoutEntry& tile = layout.tiles[k];
    try {
      if (failures[k]) std::rethrow_exception(failures[k]);
    } catch (const InputError& e) {
      throw InputError(where(tile) + e.what());
    }
    const TileImage& first = images.front();
    if (images[k].rows() != first.rows() || images[k].cols() != first.cols()) {
      throw InputError(where(tile) + tile.file + " is " + std::to_string(images[k].cols()) + " x " +
                       std::to_string(images[k].rows()) + " px but " + layout.tiles.front().file + " is " +
                       std::to_string(first.cols()) + " x " + std::to_string(first.rows()) +
                       "; all tiles of a layout come from one camera and lens: check the file");
    }
  }
  if (type != nullptr && n > 0) *type = types.front();
  return images;
}

std::string FormatTileLayout(const std::vector<TileLayoutEntry>& tiles) {
  const bool with_stage = std::all_of(tiles.begin(), tiles.end(), [](const auto& t) { return t.stage_mm.has_value(); });
  const bool with_z = with_stage && std::all_of(tiles.begin(), tiles.end(), [](const auto& t) { return t.stage_z_mm.has_value(); });
  std::string out = with_z ? "file,row,col,x,y,z\n" : with_stage ? "file,row,col,x,y\n" : "file,row,col\n";
  for (const auto& tile : tiles) {
    std::vector<std::string> fields = {tile.file, std::to_string(tile.row), std::to_string(tile.col)};
    if (with_stage) {
      fields.push_back(FormatFixed(tile.stage_mm->x(), 6));
      fields.push_back(FormatFixed(tile.stage_mm->y(), 6));
    }
    if (with_z) fields.push_back(FormatFixed(*tile.stage_z_mm, 6));
    out += CsvLine(fields);
  }
  return out;
}

}  // namespace fvm::imaging
