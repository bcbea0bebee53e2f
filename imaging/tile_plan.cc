#include "imaging/tile_plan.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::imaging {
namespace {

// Lattice arithmetic is in mm with steps of ~1 mm; 1 nm absorbs the rounding of (L - F) / s landing a hair
// above an integer, which would otherwise add a whole row of tiles.
constexpr double kEpsMm = 1e-6;

std::string Mm(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.4f", v);
  return buffer;
}

int TilesAlong(double length, double fov, double step) {
  if (length <= fov + kEpsMm) return 1;
  return 1 + static_cast<int>(std::ceil((length - fov) / step - kEpsMm / step));
}

// The runs of consecutive tiles [first, first + count) along one axis that cover [a, b] (distances from the grid's
// starting edge), all of the smallest count. Empty when [a, b] leaves the n tiles.
std::vector<std::pair<int, int>> MinimalRuns(double a, double b, int n, double fov, double step) {
  if (a < -kEpsMm || b > (n - 1) * step + fov + kEpsMm) return {};
  const int last_start = std::min(n - 1, static_cast<int>(std::floor((a + kEpsMm) / step)));
  const int end = std::max(last_start, static_cast<int>(std::ceil((b - fov - kEpsMm) / step)));
  const int count = end - last_start + 1;
  std::vector<std::pair<int, int>> runs;
  // Earlier starts also work while the run still reaches b.
  for (int first = last_start; first >= 0 && (first + count - 1) * step + fov >= b - kEpsMm; --first) {
    if (first + count <= n) runs.emplace_back(first, count);
  }
  return runs;
}

std::string PathTooLongMessage(double length, double span) {
  char text[200];
  std::snprintf(text, sizeof text, "calibration scan: a path of %.1f mm does not fit a travel of %.1f mm; give a shorter --length-mm", length, span);
  return text;
}

}  // namespace

const std::vector<Lens>& Lenses() {
  static const std::vector<Lens> lenses = {
      {"2.5x", 5.63, 2300.0}, {"5x", 2.82, 410.0}, {"10x", 1.62, 100.0},
      {"20x", 0.81, 50.0},    {"50x", 0.32, 20.0}, {"100x", 0.16, 10.0},
  };
  return lenses;
}

const Lens& FindLens(std::string_view name) {
  std::string key(name);
  std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
  if (!key.empty() && key.back() != 'x') key += 'x';
  std::string known;
  for (const Lens& lens : Lenses()) {
    if (lens.name == key) return lens;
    known += (known.empty() ? "" : ", ") + lens.name;
  }
  throw InputError("lens '" + std::string(name) + "' is unknown; use one of " + known);
}

void TilePlanOptions::Check() const {
  if (!(fov_mm > 0.0) || !std::isfinite(fov_mm)) {
    throw InputError("field of view " + std::to_string(fov_mm) + " mm: give a positive size");
  }
  if (!(overlap >= 0.0 && overlap < 1.0)) {
    throw InputError("overlap " + std::to_string(overlap) + ": give a fraction in [0, 1), e.g. 0.2 for 20 %");
  }
  if (!(seconds_per_tile >= 0.0) || !std::isfinite(seconds_per_tile)) {
    throw InputError("seconds per tile " + std::to_string(seconds_per_tile) + ": give a time >= 0");
  }
  if (pixels_x <= 0 || pixels_y <= 0 || bytes_per_pixel <= 0) {
    throw InputError("tile size and bytes per pixel must be positive");
  }
}

TileGrid PlanStitchedGrid(const Region& region, const TilePlanOptions& options) {
  options.Check();
  for (const double v : {region.x0, region.y0, region.x1, region.y1}) {
    if (!std::isfinite(v)) throw InputError("region: a coordinate is not a number; give x0,y0,x1,y1 in mm");
  }
  if (!(region.x1 > region.x0) || !(region.y1 > region.y0)) {
    throw InputError("region " + Mm(region.x0) + "," + Mm(region.y0) + "," + Mm(region.x1) + "," + Mm(region.y1) +
                     " is empty or inverted; give x0,y0,x1,y1 with x0 < x1 and y0 < y1 (mm)");
  }
  TileGrid grid;
  grid.fov_mm = options.fov_mm;
  grid.step_mm = options.fov_mm * (1.0 - options.overlap);
  grid.top_left_mm = Eigen::Vector2d(region.x0, region.y1);
  grid.cols = TilesAlong(region.x1 - region.x0, grid.fov_mm, grid.step_mm);
  grid.rows = TilesAlong(region.y1 - region.y0, grid.fov_mm, grid.step_mm);
  grid.tiles.reserve(static_cast<size_t>(grid.rows) * grid.cols);
  for (int col = 0; col < grid.cols; ++col) {
    for (int row = 0; row < grid.rows; ++row) {
      const Eigen::Vector2d centre(region.x0 + 0.5 * grid.fov_mm + col * grid.step_mm,
                                   region.y1 - 0.5 * grid.fov_mm - row * grid.step_mm);
      grid.tiles.push_back(Tile{static_cast<int>(grid.tiles.size()), row, col, centre});
    }
  }
  return grid;
}

StitchingFreePlan PlanStitchingFree(const TileGrid& grid, const std::vector<Feature>& features) {
  std::set<int> chosen;
  StitchingFreePlan plan;
  for (const Feature& feature : features) {
    if (!(feature.radius_mm >= 0.0) || !feature.centre_mm.allFinite()) {
      throw InputError("feature " + std::to_string(feature.id) + ": centre and radius must be finite, radius >= 0");
    }
    const double u = feature.centre_mm.x() - grid.top_left_mm.x();  // from the left edge, +X
    const double v = grid.top_left_mm.y() - feature.centre_mm.y();  // from the top edge, -Y
    const double r = feature.radius_mm;
    const auto cols = MinimalRuns(u - r, u + r, grid.cols, grid.fov_mm, grid.step_mm);
    const auto rows = MinimalRuns(v - r, v + r, grid.rows, grid.fov_mm, grid.step_mm);
    if (cols.empty() || rows.empty()) {
      throw InputError("feature " + std::to_string(feature.id) + " at (" + Mm(feature.centre_mm.x()) + ", " +
                       Mm(feature.centre_mm.y()) + ") mm, radius " + Mm(r) +
                       " mm, is not wholly inside the tile grid; enlarge the region to contain it");
    }
    std::vector<int> best;
    size_t best_new = SIZE_MAX;
    for (const auto& [c0, nc] : cols) {
      for (const auto& [r0, nr] : rows) {
        std::vector<int> option;
        size_t fresh = 0;
        for (int col = c0; col < c0 + nc; ++col) {
          for (int row = r0; row < r0 + nr; ++row) {
            option.push_back(grid.At(row, col).index);
            fresh += chosen.count(option.back()) == 0;
          }
        }
        if (fresh < best_new) best_new = fresh, best = option;
      }
    }
    chosen.insert(best.begin(), best.end());
    std::sort(best.begin(), best.end());
    plan.covers.push_back(FeatureCover{feature.id, best});
  }
  for (const int index : chosen) plan.tiles.push_back(grid.tiles[static_cast<size_t>(index)]);
  return plan;
}

double ParseOverlap(std::string_view text, std::string_view what) {
  std::string_view s = TrimBlanks(text);
  bool percent = false;
  if (!s.empty() && s.back() == '%') {
    percent = true;
    s.remove_suffix(1);
  }
  // '.' is the decimal mark whatever the locale: std::stod follows the C locale and under a German one stops at
  // the '.' of 0.2.
  const std::optional<double> parsed = ParseDouble(s);
  const std::string name(what);
  if (!parsed || !std::isfinite(*parsed)) {
    throw InputError(name + " '" + std::string(text) + "': not a number; give a fraction (0.2) or percent (20)");
  }
  double value = *parsed;
  if (percent || value >= 1.0) value /= 100.0;
  if (!(value > 0.0)) {
    throw InputError(name + " '" + std::string(text) +
                     "': tiles must overlap to be stitched; give the overlap the scan used, e.g. 0.2 for 20 %");
  }
  if (!(value < 1.0)) {
    throw InputError(name + " '" + std::string(text) + "': an overlap of 100 % or more is no scan; give e.g. 20");
  }
  return value;
}

ScanCost EstimateScan(int tiles, const TilePlanOptions& options) {
  ScanCost cost;
  cost.tiles = tiles;
  cost.seconds = tiles * options.seconds_per_tile;
  cost.bytes = static_cast<double>(tiles) * options.pixels_x * options.pixels_y * options.bytes_per_pixel;
  return cost;
}

void CalibrationScanOptions::Check() const {
  const Eigen::Vector2d span = travel_max_mm - travel_min_mm;
  if (!(span.minCoeff() > 0.0) || !span.allFinite()) throw InputError("calibration scan: give a travel of positive size, e.g. 200x200");
  if (!(length_mm > 0.0) || length_mm > span.minCoeff()) {
    throw InputError(PathTooLongMessage(length_mm, span.minCoeff()));
  }
  if (heights_mm.empty()) throw InputError("calibration scan: give at least one height");
}

std::vector<ScanPath> PlanCalibrationScans(const CalibrationScanOptions& scan, const TilePlanOptions& options) {
  scan.Check();
  options.Check();
  const double step = options.fov_mm * (1.0 - options.overlap);
  const Eigen::Vector2d centre = 0.5 * (scan.travel_min_mm + scan.travel_max_mm);
  // Steps along a path of `length` at `step` per axis: the first tile's centre half a length before the centre.
  const auto straight = [&](const std::string& name, const Eigen::Vector2d& direction, double length, double z, int kind) {
    ScanPath path{name, {}, z};
    const int count = 1 + static_cast<int>(std::ceil(length / step - 1e-9));
    const Eigen::Vector2d start = centre - 0.5 * step * (count - 1) * direction;
    for (int k = 0; k < count; ++k) {
      Tile t;
      t.index = k;
      t.row = kind == 1 ? 0 : k;
      t.col = kind == 2 ? 0 : k;
      t.centre_mm = start + step * k * direction;
      path.tiles.push_back(t);
    }
    return path;
  };
  std::vector<ScanPath> paths;
  for (size_t h = 0; h < scan.heights_mm.size(); ++h) {
    const std::string suffix = h == 0 ? "" : "-z" + std::to_string(h + 1);
    const double z = scan.heights_mm[h];
    paths.push_back(straight("row" + suffix, {1.0, 0.0}, scan.length_mm, z, 1));
    paths.push_back(straight("column" + suffix, {0.0, -1.0}, scan.length_mm, z, 2));
    // Per axis a step of `step`: the diagonal's length along each axis is length / sqrt(2).
    paths.push_back(straight("diagonal" + suffix, {1.0, -1.0}, scan.length_mm / std::sqrt(2.0), z, 3));
  }
  return paths;
}

}  // namespace fvm::imaging
