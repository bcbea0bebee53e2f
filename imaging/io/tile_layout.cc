#include "imaging/io/tile_layout.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string_view>
#include <utility>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

std::vector<std::string> Split(std::string_view line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t end = line.find(',', start);
    fields.emplace_back(Trim(line.substr(start, end == std::string_view::npos ? end : end - start)));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return fields;
}

std::optional<double> ParseDouble(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || error != std::errc() || end != s.data() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<int> ParseIndex(std::string_view s) {
  int value = 0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || error != std::errc() || end != s.data() + s.size() || value < 0) return std::nullopt;
  return value;
}

}  // namespace

TileLayout ReadTileLayout(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in || std::filesystem::is_directory(path)) {
    throw InputError(name + ": cannot read the tile layout; give a CSV file,row,col[,x,y] (fvm tiles plan -o writes "
                            "one)");
  }
  TileLayout layout;
  layout.source = name;
  const auto fail = [&](int line, const std::string& problem) {
    throw InputError(name + ":" + std::to_string(line) + ": " + problem);
  };
  std::map<std::string, int> column;
  std::map<std::pair<int, int>, int> seen;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (Trim(text).empty() || Trim(text).front() == '#') continue;
    const std::vector<std::string> fields = Split(text);
    if (column.empty()) {
      for (size_t i = 0; i < fields.size(); ++i) {
        std::string key = fields[i];
        std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
        column.emplace(key, static_cast<int>(i));
      }
      for (const char* required : {"file", "row", "col"}) {
        if (!column.count(required)) {
          fail(line, std::string("the header has no '") + required + "' column; the layout needs file,row,col[,x,y]");
        }
      }
      if (column.count("x") != column.count("y")) fail(line, "the header has only one of x, y; give both or neither");
      continue;
    }
    const auto field = [&](const char* key) -> std::string {
      const size_t i = static_cast<size_t>(column.at(key));
      if (i >= fields.size()) fail(line, std::string("the row is short: no '") + key + "' value");
      return fields[i];
    };
    TileLayoutEntry entry;
    entry.line = line;
    entry.file = field("file");
    if (entry.file.empty()) fail(line, "empty file name");
    const auto row = ParseIndex(field("row"));
    const auto col = ParseIndex(field("col"));
    if (!row || !col) fail(line, "row and col must be integers >= 0 (row 0 = highest Y, col 0 = lowest X)");
    entry.row = *row;
    entry.col = *col;
    if (column.count("x")) {
      const auto x = ParseDouble(field("x"));
      const auto y = ParseDouble(field("y"));
      if (!x || !y) fail(line, "x and y must be numbers (mm)");
      entry.stage_mm = Eigen::Vector2d(*x, *y);
    }
    const auto [it, fresh] = seen.emplace(std::make_pair(entry.row, entry.col), line);
    if (!fresh) {
      fail(line, "tile row " + std::to_string(entry.row) + " col " + std::to_string(entry.col) +
                     " is given twice (first on line " + std::to_string(it->second) + "); give each tile once");
    }
    layout.rows = std::max(layout.rows, entry.row + 1);
    layout.cols = std::max(layout.cols, entry.col + 1);
    layout.tiles.push_back(std::move(entry));
  }
  if (column.empty()) throw InputError(name + ": empty; the layout needs a header file,row,col[,x,y] and tiles");
  if (layout.tiles.empty()) throw InputError(name + ": no tiles after the header");
  return layout;
}

void CheckLayoutComplete(const TileLayout& layout) {
  std::vector<char> present(static_cast<size_t>(layout.rows) * layout.cols, 0);
  for (const auto& tile : layout.tiles) present[static_cast<size_t>(tile.row) * layout.cols + tile.col] = 1;
  for (int row = 0; row < layout.rows; ++row) {
    for (int col = 0; col < layout.cols; ++col) {
      if (!present[static_cast<size_t>(row) * layout.cols + col]) {
        throw InputError(layout.source + ": the layout has a hole: no tile at row " + std::to_string(row) + " col " +
                         std::to_string(col) + " of the " + std::to_string(layout.rows) + " x " +
                         std::to_string(layout.cols) +
                         " grid; stitching needs a full grid (stitching-free layouts are not stitched)");
      }
    }
  }
}

std::string FormatTileLayout(const std::vector<TileLayoutEntry>& tiles) {
  const bool with_stage = std::all_of(tiles.begin(), tiles.end(), [](const auto& t) { return t.stage_mm.has_value(); });
  std::string out = with_stage ? "file,row,col,x,y\n" : "file,row,col\n";
  char buffer[256];
  for (const auto& tile : tiles) {
    if (with_stage) {
      std::snprintf(buffer, sizeof(buffer), "%s,%d,%d,%.6f,%.6f\n", tile.file.c_str(), tile.row, tile.col,
                    tile.stage_mm->x(), tile.stage_mm->y());
    } else {
      std::snprintf(buffer, sizeof(buffer), "%s,%d,%d\n", tile.file.c_str(), tile.row, tile.col);
    }
    out += buffer;
  }
  return out;
}

}  // namespace fvm::imaging
