#include "imaging/io/fiji_tile_configuration.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <tuple>
#include <utility>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::imaging {
namespace {

// Positions beyond a billion pixels are a unit slip or a broken export, not a stage's travel; their squares must
// stay far from overflow in the solve.
constexpr double kMaxFijiCoordinatePx = 1e9;

struct FijiLine {
  const std::string& source;
  int number;
  [[noreturn]] void Fail(const std::string& problem) const {
    throw InputError(source + ":" + std::to_string(number) + ": " + problem);
  }
};

// `text`'s fields between `delimiter`s, each without blanks at either end.
std::vector<std::string_view> SplitTrimmed(std::string_view text, char delimiter) {
  std::vector<std::string_view> fields;
  for (size_t begin = 0;;) {
    const size_t end = text.find(delimiter, begin);
    fields.push_back(TrimBlanks(text.substr(begin, end == std::string_view::npos ? end : end - begin)));
    if (end == std::string_view::npos) return fields;
    begin = end + 1;
  }
}

// Whether a line (trimmed) is the `dim = N` line.
bool IsDimensionLine(std::string_view line) {
  return line.starts_with("dim") && TrimBlanks(line.substr(3)).starts_with("=");
}

// The `dim = N` line's N (2 or 3).
int ParseFijiDimension(std::string_view line, const FijiLine& at) {
  const size_t equals = line.find('=');
  const std::optional<std::int64_t> dim =
      equals == std::string_view::npos ? std::nullopt : ParseInt(line.substr(equals + 1));
  if (TrimBlanks(line.substr(0, equals)) != "dim" || !dim) {
    at.Fail("cannot read " + QuotedForMessage(line) + " as the dimension; write 'dim = 2'");
  }
  const std::int64_t value = dim.value_or(0);
  if (value != 2 && value != 3) {
    at.Fail("dim = " + std::to_string(value) + ": fvm stitch places 2-D tiles; give 'dim = 2' (or 3 with every z equal)");
  }
  return static_cast<int>(value);
}

// `name; series; (x, y[, z])`, as Fiji's Stitching_Grid reads it: three fields split at ';', the coordinates in
// parentheses split at ','.
FijiTile ParseFijiTileLine(std::string_view line, int dim, const FijiLine& at, std::optional<double>* z) {
  const auto expected = [&] {
    at.Fail("cannot read " + QuotedForMessage(line) + " as a tile; write 'name; ; (x, y)'" +
            (dim == 3 ? " with (x, y, z) under dim = 3" : ""));
  };
  const std::vector<std::string_view> fields = SplitTrimmed(line, ';');
  if (fields.size() != 3) expected();
  FijiTile tile;
  tile.file = std::string(fields[0]);
  tile.line = at.number;
  if (tile.file.empty()) at.Fail("a tile without an image name; write 'name; ; (x, y)'");
  if (!fields[1].empty()) {
    at.Fail("tile " + tile.file + " is series " + std::string(fields[1]) +
            " of a multi-series file; fvm reads one image a file: export each tile as an image");
  }
  std::string_view point = fields[2];
  if (point.size() < 2 || point.front() != '(' || point.back() != ')') expected();
  point = point.substr(1, point.size() - 2);
  std::vector<double> values;
  for (const std::string_view text : SplitTrimmed(point, ',')) {
    const std::optional<double> v = ParseDouble(text);
    if (!v || !std::isfinite(*v) || std::abs(*v) > kMaxFijiCoordinatePx) {
      at.Fail("tile " + tile.file + ": coordinate " + QuotedForMessage(text) +
              " is not a position in pixels (a finite number within 1e9); check the line");
    }
    values.push_back(*v);
  }
  if (static_cast<int>(values.size()) != dim) {
    at.Fail("tile " + tile.file + " has " + std::to_string(values.size()) + " coordinates under dim = " +
            std::to_string(dim) + "; give " + (dim == 2 ? "(x, y)" : "(x, y, z)"));
  }
  tile.position_px = Eigen::Vector2d(values[0], values[1]);
  if (dim == 3) {
    if (!*z) *z = values[2];
    if (values[2] != **z) {
      at.Fail("tile " + tile.file + " is at z = " + FormatShortest(values[2]) + " px, the first tile at z = " +
              FormatShortest(**z) + ": tiles in several planes are image stacks; fvm stitch places 2-D tiles in one "
              "plane");
    }
  }
  return tile;
}

// A byte-order mark, which Windows editors put before the first line.
std::string_view WithoutByteOrderMark(std::string_view text) {
  return text.starts_with("\xEF\xBB\xBF") ? text.substr(3) : text;
}

// One axis's node indices: see FijiTileLayout. `what` names the axis's lines ("column", "row") in messages.
std::vector<int> FijiAxisNodes(const FijiTileConfiguration& config, int axis, double pitch, const char* what) {
  const size_t n = config.tiles.size();
  const auto at = [&](size_t i) { return config.tiles[i].position_px[axis]; };
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return at(a) < at(b); });
  std::vector<int> cluster_of(n);
  std::vector<std::vector<size_t>> clusters;
  for (size_t k = 0; k < n; ++k) {
    if (k == 0 || at(order[k]) - at(order[k - 1]) >= pitch / 3.0) clusters.emplace_back();
    clusters.back().push_back(order[k]);
    cluster_of[order[k]] = static_cast<int>(clusters.size()) - 1;
  }
  const char* coordinate = axis == 0 ? "x" : "y";
  const auto refuse = [&](size_t tile, double from_node) {
    const FijiTile& t = config.tiles[tile];
    throw InputError(fmt::format("{}:{}: tile {} at {} = {} px is {:.1f} px from the nearest {} of the grid (pitch "
                                 "{:.1f} px): it lies on no node, within a third of a pitch; check its position and "
                                 "--overlap",
                                 config.source, t.line, t.file, coordinate, FormatShortest(t.position_px[axis]),
                                 from_node, what, pitch));
  };
  // Each column's centre the median of its tiles; a tile a third of a pitch or more from it lies between nodes.
  std::vector<double> centre(clusters.size());
  for (size_t c = 0; c < clusters.size(); ++c) {
    const std::vector<size_t>& members = clusters[c];  // sorted by coordinate
    const size_t m = members.size();
    centre[c] = (at(members[(m - 1) / 2]) + at(members[m / 2])) / 2.0;
    for (size_t tile : members) {
      if (std::abs(at(tile) - centre[c]) >= pitch / 3.0) refuse(tile, std::abs(at(tile) - centre[c]));
    }
  }
  // Indices counted outwards from the first tile's column, by the pitches between neighbouring columns: the column
  // farther from the first tile is the one refused when a distance is no whole number of pitches.
  const int first = cluster_of[0];
  std::vector<int> index(clusters.size(), 0);
  const auto step = [&](int from, int to) {
    const double pitches = (centre[static_cast<size_t>(to)] - centre[static_cast<size_t>(from)]) / pitch;
    const double whole = std::round(pitches);
    if (std::abs(pitches - whole) >= 1.0 / 3.0) {
      const size_t tile = *std::min_element(clusters[static_cast<size_t>(to)].begin(),
                                            clusters[static_cast<size_t>(to)].end());  // first in the file
      refuse(tile, std::abs(pitches - whole) * pitch);
    }
    // Within the bounds of a layout before any index is formed (coordinates up to 1e9 px over a pitch of a pixel).
    const double at_index = index[static_cast<size_t>(from)] + whole;
    if (std::abs(at_index) >= kMaxTilesPerAxis) {
      const FijiTile& t = config.tiles[clusters[static_cast<size_t>(to)].front()];
      throw InputError(fmt::format("{}:{}: tile {} is {:.0f} pitches of {:.1f} px from the first tile along {}: more {}s "
                                   "than a layout may span ({}); check the positions and --overlap",
                                   config.source, t.line, t.file, at_index, pitch, coordinate, what,
                                   kMaxTilesPerAxis));
    }
    index[static_cast<size_t>(to)] = static_cast<int>(at_index);
  };
  for (int c = first + 1; c < static_cast<int>(clusters.size()); ++c) step(c - 1, c);
  for (int c = first - 1; c >= 0; --c) step(c + 1, c);
  const int lowest = *std::min_element(index.begin(), index.end());
  std::vector<int> nodes(n);
  for (size_t i = 0; i < n; ++i) nodes[i] = index[static_cast<size_t>(cluster_of[i])] - lowest;
  return nodes;
}

}  // namespace

bool IsFijiTileConfiguration(const std::filesystem::path& path) {
  std::string head;
  try {
    head = ReadFileHead(path, size_t{1} << 16);
  } catch (const InputError&) {
    return false;
  }
  const std::string_view text = WithoutByteOrderMark(head);
  for (size_t begin = 0; begin < text.size();) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    const std::string_view line = TrimBlanks(text.substr(begin, end - begin));
    begin = end + 1;
    if (line.empty() || line.front() == '#') continue;
    return IsDimensionLine(line);
  }
  return false;
}

FijiTileConfiguration ParseFijiTileConfiguration(std::string_view text, const std::string& source) {
  text = WithoutByteOrderMark(text);
  FijiTileConfiguration config;
  config.source = source;
  bool dim_given = false;
  std::optional<double> z;
  std::map<std::string, int> named;
  int number = 0;
  for (size_t begin = 0; begin < text.size();) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    const std::string_view line = TrimBlanks(text.substr(begin, end - begin));
    begin = end + 1;
    const FijiLine at{source, ++number};
    if (line.empty() || line.front() == '#') continue;
    if (IsDimensionLine(line)) {
      if (dim_given) at.Fail("a second 'dim =' line; give the dimension once, before the tiles");
      config.dim = ParseFijiDimension(line, at);
      dim_given = true;
      continue;
    }
    if (line.starts_with("multiseries")) {
      if (line.find("true") != std::string_view::npos) {
        at.Fail("a multi-series configuration: fvm reads one image a file; export each tile as an image");
      }
      continue;
    }
    if (!dim_given) at.Fail("a tile before the 'dim = 2' line; a Fiji tile configuration gives its dimension first");
    FijiTile tile = ParseFijiTileLine(line, config.dim, at, &z);
    const auto [it, fresh] = named.emplace(tile.file, tile.line);
    if (!fresh) {
      at.Fail("tile " + tile.file + " is given twice (first on line " + std::to_string(it->second) +
              "); give each tile once");
    }
    if (config.tiles.size() >= static_cast<size_t>(kMaxLayoutTiles)) {
      at.Fail("more than " + std::to_string(kMaxLayoutTiles) + " tiles; a layout holds at most that many");
    }
    config.tiles.push_back(std::move(tile));
  }
  if (config.tiles.empty()) {
    throw InputError(source + ": no tiles; a Fiji tile configuration lists one 'name; ; (x, y)' line a tile");
  }
  return config;
}

FijiTileConfiguration ReadFijiTileConfiguration(const std::filesystem::path& path) {
  return ParseFijiTileConfiguration(ReadFileBytes(path, size_t{1} << 28), path.string());
}

namespace {

// Each axis's pitch as its own gaps show it (see PitchFromGaps); NaN along an axis without a step (one column or row).
Eigen::Vector2d OwnGapPitches(const FijiTileConfiguration& config) {
  std::vector<double> gaps[2];
  double widest = 0.0;
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> v;
    for (const FijiTile& t : config.tiles) v.push_back(t.position_px[axis]);
    std::sort(v.begin(), v.end());
    for (size_t k = 1; k < v.size(); ++k) gaps[axis].push_back(v[k] - v[k - 1]);
    for (double g : gaps[axis]) widest = std::max(widest, g);
  }
  Eigen::Vector2d pitch(NAN, NAN);
  if (!(widest > 0.0)) return pitch;  // one tile, or all on one point
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> steps;
    for (double g : gaps[axis]) {
      if (g > widest / 6.0) steps.push_back(g);
    }
    if (steps.empty()) continue;
    std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
    pitch[axis] = steps[steps.size() / 2];
  }
  return pitch;
}

}  // namespace

Eigen::Vector2d PitchFromGaps(const FijiTileConfiguration& config) {
  Eigen::Vector2d pitch = OwnGapPitches(config);
  if (std::isnan(pitch.x())) pitch.x() = pitch.y();
  if (std::isnan(pitch.y())) pitch.y() = pitch.x();
  if (std::isnan(pitch.x())) pitch = Eigen::Vector2d::Ones();  // one node: any pitch (two tiles there are refused)
  return pitch;
}

TileLayout FijiTileLayout(const FijiTileConfiguration& config, std::optional<Eigen::Vector2d> pitch_px) {
  const Eigen::Vector2d pitch = pitch_px.value_or(PitchFromGaps(config));
  const std::vector<int> cols = FijiAxisNodes(config, 0, pitch.x(), "column");
  const std::vector<int> rows = FijiAxisNodes(config, 1, pitch.y(), "row");
  // A pitch the positions step over two or more at a time everywhere (a wrong --overlap: the tiles then lie two nodes
  // apart, with no neighbour to register) is refused, saying so.
  for (const auto& [nodes, what, coordinate, along] :
       {std::tuple(&cols, "columns", "x", pitch.x()), std::tuple(&rows, "rows", "y", pitch.y())}) {
    std::vector<int> present(*nodes);
    std::sort(present.begin(), present.end());
    present.erase(std::unique(present.begin(), present.end()), present.end());
    int nearest = std::numeric_limits<int>::max();
    for (size_t k = 1; k < present.size(); ++k) nearest = std::min(nearest, present[k] - present[k - 1]);
    if (present.size() >= 2 && nearest >= 2) {
      throw InputError(fmt::format("{}: no two {} of the grid are neighbours: the nearest lie {} pitches of {:.1f} px "
                                   "apart along {}; check --overlap (the pitch is the tile size times 1 - overlap), or "
                                   "give the tiles between them",
                                   config.source, what, nearest, along, coordinate));
    }
  }
  TileLayout layout;
  layout.source = config.source;
  std::map<std::pair<int, int>, size_t> seen;
  for (size_t i = 0; i < config.tiles.size(); ++i) {
    const FijiTile& t = config.tiles[i];
    TileLayoutEntry entry;
    entry.file = t.file;
    entry.row = rows[i];
    entry.col = cols[i];
    entry.line = t.line;
    entry.nominal_px = t.position_px;
    const auto [it, fresh] = seen.emplace(std::make_pair(entry.row, entry.col), i);
    if (!fresh) {
      const FijiTile& other = config.tiles[it->second];
      throw InputError(fmt::format("{}:{}: tile {} and tile {} (line {}) are both at row {} col {} of the grid "
                                   "(pitch {:.1f} x {:.1f} px): give each node one tile, or check the positions and "
                                   "--overlap",
                                   config.source, t.line, t.file, other.file, other.line, entry.row, entry.col,
                                   pitch.x(), pitch.y()));
    }
    if (entry.row >= kMaxTilesPerAxis || entry.col >= kMaxTilesPerAxis ||
        std::int64_t{std::max(layout.rows, entry.row + 1)} * std::max(layout.cols, entry.col + 1) > kMaxLayoutTiles) {
      throw InputError(fmt::format("{}:{}: tile {} is at row {} col {}: the grid would span more than the {} tiles "
                                   "a layout may; check the positions",
                                   config.source, t.line, t.file, entry.row, entry.col, kMaxLayoutTiles));
    }
    layout.rows = std::max(layout.rows, entry.row + 1);
    layout.cols = std::max(layout.cols, entry.col + 1);
    layout.tiles.push_back(std::move(entry));
  }
  return layout;
}

std::string FormatFijiTileConfiguration(const std::vector<std::string>& files,
                                        const std::vector<Eigen::Vector2d>& positions_px) {
  std::string out =
      "# Define the number of dimensions we are working on\ndim = 2\n\n# Define the image coordinates\n";
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string& file = files[i];
    if (TrimBlanks(file).empty() || TrimBlanks(file) != file ||
        file.find_first_of(";\n\r") != std::string::npos) {
      throw InputError("tile " + QuotedForMessage(file) +
                       ": Fiji cannot read this name back (a ';', a line break, or blanks at either end); rename the "
                       "tile or write the positions as CSV");
    }
    out += fmt::format("{}; ; ({}, {})\n", file, FormatFixed(positions_px[i].x(), 4),
                       FormatFixed(positions_px[i].y(), 4));
  }
  return out;
}

}  // namespace fvm::imaging
