#pragma once
// Tile grids cut from real images at known whole-pixel positions, so that the truth is exact and registration can
// be judged to the pixel on real texture (issue 42). The sources are real: one confocal tile of
// ../shared/realdata/tiles/confocal-3x4 (1024 x 1024 px) and the starrynight strip fused at Fiji's positions
// (about 2700 x 929 px). The cuts carry what a real scan adds: thin overlaps (11-15 px of 245 x 183 px tiles, ~6 %),
// a stage that puts each row and column sideways by more than the overlap (5-20 px), vignetting, exposure
// differences and camera noise; optionally most of the scene masked to a flat, noisy background (sparse content,
// cells on an empty field). Empty sources when ../shared is absent, so that the tests skip.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "imaging/grid_tile.h"
#include "imaging/io/tile_image.h"
#include "imaging/tile_mosaic.h"
#include "tests/support/starrynight_strip.h"

namespace fvm::imaging::testing {

struct CutTileOptions {
  int rows = 5, cols = 4;
  int width = 245, height = 183;
  int min_overlap_px = 11, max_overlap_px = 15;  // true overlap of each neighbour pair along its step
  double nominal_overlap = 0.06;  // what the user declares (fvm stitch --overlap 6): the nominal grid
  // Each row sits sideways (x) and each column down (y) by up to this (px, uniform): a stage whose rows and
  // columns do not line up, by more than the overlap. Neighbours then differ sideways by up to twice as much.
  double jitter_px = 12.0;
  double vignetting = 0.3;   // up to this fall-off of the gain at a tile's corners (uniform per tile)
  double exposure = 0.15;    // gain 1 +- this, offset +- this of the source's range (uniform per tile)
  double noise = 0.02;       // camera noise, standard deviation as a fraction of the source's range
  // > 0: only this fraction of the scene (about) keeps its content, in round patches of 30-80 px radius with soft
  // edges; the rest is the source's median, a flat background under the camera noise.
  double sparse_fraction = 0.0;
  uint32_t seed = 1;
};

struct CutTiles {
  std::vector<TileImage> images;
  std::vector<GridTile> tiles;           // row-major, nominal from the declared overlap, tile 0 at the origin
  std::vector<Eigen::Vector2d> truth_px;  // where each tile was cut, relative to tile 0's cut
};

// A uniform draw in [0, 1) from the generator's 32 bits: the same numbers on every standard library.
inline double CutUniform(std::mt19937& rng) { return static_cast<double>(rng()) / 4294967296.0; }
inline double CutGaussian(std::mt19937& rng) {
  const double u1 = std::max(CutUniform(rng), 1e-300), u2 = CutUniform(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

inline std::filesystem::path RealTilesDir() { return std::filesystem::path(FVM_REALDATA_DIR) / "tiles"; }

// One real confocal tile (1024 x 1024 px, colour averaged to grey); empty when absent.
inline TileImage ConfocalSource() {
  const std::filesystem::path file = RealTilesDir() / "confocal-3x4" / "x100_epr-jerem_10pct_001_A001_I.tif";
  if (!std::filesystem::exists(file)) return {};
  return ReadTileImage(file);
}

// The starrynight strip fused at Fiji's positions, cropped to where every row is covered; empty when absent.
inline TileImage StarrynightSource() {
  const RealStrip strip = LoadStarrynight();
  if (strip.images.empty()) return {};
  const Mosaic mosaic = FuseTiles(strip.images, strip.fiji_px);
  const TileImage& m = mosaic.image;
  // The feathering leaves the outermost pixels of the mosaic without weight (NaN) and the tiles' different heights
  // leave its top and bottom ragged: rows mostly covered first, then columns, then rows wholly covered.
  int top = 0, bottom = static_cast<int>(m.rows()), left = 0, right = static_cast<int>(m.cols());
  const auto finite_in_row = [&](int y) { return m.row(y).segment(left, right - left).array().isFinite().count(); };
  const auto col_full = [&](int x) { return m.col(x).segment(top, bottom - top).array().isFinite().all(); };
  while (top < bottom && finite_in_row(top) < 0.99 * (right - left)) ++top;
  while (bottom > top && finite_in_row(bottom - 1) < 0.99 * (right - left)) --bottom;
  while (left < right && !col_full(left)) ++left;
  while (right > left && !col_full(right - 1)) --right;
  while (top < bottom && finite_in_row(top) < right - left) ++top;
  while (bottom > top && finite_in_row(bottom - 1) < right - left) --bottom;
  return m.block(top, left, bottom - top, right - left);
}

// Cuts options.rows x options.cols tiles from `source`. Throws std::invalid_argument when they do not fit.
inline CutTiles CutTileGrid(const TileImage& source, const CutTileOptions& o) {
  std::mt19937 rng(o.seed);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * CutUniform(rng); };
  const auto whole = [&](int lo, int hi) { return lo + static_cast<int>(rng() % static_cast<uint32_t>(hi - lo + 1)); };
  // Steps: each pair's own overlap; sideways: one offset per row (x) and per column (y).
  std::vector<int> row_shift(static_cast<size_t>(o.rows)), col_shift(static_cast<size_t>(o.cols));
  for (auto& s : row_shift) s = static_cast<int>(std::lround(uniform(-o.jitter_px, o.jitter_px)));
  for (auto& s : col_shift) s = static_cast<int>(std::lround(uniform(-o.jitter_px, o.jitter_px)));
  std::vector<Eigen::Vector2i> at(static_cast<size_t>(o.rows * o.cols));
  std::vector<int> x_of_col(static_cast<size_t>(o.cols), 0), y_of_row(static_cast<size_t>(o.rows), 0);
  for (int c = 1; c < o.cols; ++c) x_of_col[c] = x_of_col[c - 1] + o.width - whole(o.min_overlap_px, o.max_overlap_px);
  for (int r = 1; r < o.rows; ++r) y_of_row[r] = y_of_row[r - 1] + o.height - whole(o.min_overlap_px, o.max_overlap_px);
  int min_x = 0, min_y = 0, max_x = 0, max_y = 0;
  for (int r = 0; r < o.rows; ++r) {
    for (int c = 0; c < o.cols; ++c) {
      const Eigen::Vector2i p(x_of_col[c] + row_shift[r], y_of_row[r] + col_shift[c]);
      at[static_cast<size_t>(r * o.cols + c)] = p;
      min_x = std::min(min_x, p.x()), min_y = std::min(min_y, p.y());
      max_x = std::max(max_x, p.x()), max_y = std::max(max_y, p.y());
    }
  }
  const int span_x = max_x - min_x + o.width, span_y = max_y - min_y + o.height;
  if (span_x > source.cols() || span_y > source.rows()) {
    throw std::invalid_argument("CutTileGrid: the grid does not fit in the source image");
  }
  // Where in the source the grid starts: anywhere it fits.
  const int x0 = whole(0, static_cast<int>(source.cols()) - span_x) - min_x;
  const int y0 = whole(0, static_cast<int>(source.rows()) - span_y) - min_y;

  // The source's range and median, for the noise, the exposure and the flat background.
  std::vector<float> values(source.data(), source.data() + source.size());
  std::sort(values.begin(), values.end());
  const double lo = values[values.size() / 100], hi = values[values.size() * 99 / 100];
  const double median = values[values.size() / 2], range = std::max(hi - lo, 1e-6);
  TileImage scene = source;
  if (o.sparse_fraction > 0.0) {
    // Patches until about sparse_fraction of the grid's area is covered (patches overlap, so draw a little more).
    const double area = static_cast<double>(span_x) * span_y;
    std::vector<Eigen::Vector3d> patches;  // x, y, radius in the source
    double covered = 0.0;
    while (covered < o.sparse_fraction * area) {
      const double radius = uniform(30.0, 80.0);
      patches.push_back({x0 + min_x + uniform(0.0, span_x), y0 + min_y + uniform(0.0, span_y), radius});
      covered += 3.14159 * radius * radius * 0.85;
    }
    Eigen::MatrixXd keep = Eigen::MatrixXd::Zero(scene.rows(), scene.cols());
    for (const auto& p : patches) {
      const int ya = std::max(0, static_cast<int>(p.y() - p.z())), yb = std::min<int>(scene.rows(), p.y() + p.z() + 1);
      const int xa = std::max(0, static_cast<int>(p.x() - p.z())), xb = std::min<int>(scene.cols(), p.x() + p.z() + 1);
      for (int y = ya; y < yb; ++y) {
        for (int x = xa; x < xb; ++x) {
          const double d = std::hypot(x - p.x(), y - p.y());
          keep(y, x) = std::max(keep(y, x), std::clamp((p.z() - d) / 8.0, 0.0, 1.0));  // 8 px soft edge
        }
      }
    }
    scene = (median + keep.array() * (scene.cast<double>().array() - median)).cast<float>().matrix();
  }
  CutTiles out;
  const Eigen::Vector2i first = at.front();
  for (int r = 0; r < o.rows; ++r) {
    for (int c = 0; c < o.cols; ++c) {
      const Eigen::Vector2i p = at[static_cast<size_t>(r * o.cols + c)];
      const double gain = 1.0 + uniform(-o.exposure, o.exposure);
      const double offset = uniform(-o.exposure, o.exposure) * range;
      const double fall = uniform(0.0, o.vignetting);
      const double cx = 0.5 * (o.width - 1) + uniform(-0.1, 0.1) * o.width;
      const double cy = 0.5 * (o.height - 1) + uniform(-0.1, 0.1) * o.height;
      const double corner = cx * cx + cy * cy;
      TileImage tile(o.height, o.width);
      for (int y = 0; y < o.height; ++y) {
        for (int x = 0; x < o.width; ++x) {
          const double shade = 1.0 - fall * ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / corner;
          const double v = scene(y0 + p.y() + y, x0 + p.x() + x);
          tile(y, x) = static_cast<float>(gain * shade * v + offset + o.noise * range * CutGaussian(rng));
        }
      }
      out.images.push_back(std::move(tile));
      out.truth_px.push_back((p - first).cast<double>());
      out.tiles.push_back({r, c,
                           Eigen::Vector2d(c * o.width * (1.0 - o.nominal_overlap),
                                           r * o.height * (1.0 - o.nominal_overlap))});
    }
  }
  return out;
}

}  // namespace fvm::imaging::testing
