#include "artefacts/simulation/height_tile_synthesis.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace fvm::artefacts {

void HeightTileOptions::Check() const {
  if (rows < 0 || cols < 0 || size < 16) throw std::invalid_argument("height tiles: rows, cols >= 0, size >= 16 px");
  if (!(overlap > 0.0 && overlap < 1.0)) throw std::invalid_argument("height tiles: overlap in (0, 1)");
  if (!(position_sigma_px >= 0.0) || !(noise_mm >= 0.0)) {
    throw std::invalid_argument("height tiles: stage error and noise >= 0");
  }
  surface.Check();
}

SynthesizedHeightTiles SynthesizeHeightTiles(const Artefact& artefact, const HeightTileOptions& options) {
  options.Check();
  SynthesizedHeightTiles out;
  CalotteSurfaceOptions surface = options.surface;
  surface.seed = options.seed;
  out.surface = RenderCalotteSurface(artefact, surface);
  const imaging::HeightMap& map = out.surface.map;
  const int step = static_cast<int>(std::lround(options.size * (1.0 - options.overlap)));
  // The grid starts a little inside the map, room for the first tiles' stage errors; pixels beyond the map are
  // beyond the part: invalid, as the instrument records them.
  const int border = static_cast<int>(std::ceil(5.0 * options.position_sigma_px)) + 1;
  const auto cover = [&](int pixels) {
    return std::max(1, static_cast<int>(std::ceil(static_cast<double>(pixels - 2 * border - options.size) / step)) + 1);
  };
  const int rows = options.rows > 0 ? options.rows : cover(map.size_y);
  const int cols = options.cols > 0 ? options.cols : cover(map.size_x);
  const auto height = [&](int ix, int iy) {
    return ix >= 0 && iy >= 0 && ix < map.size_x && iy < map.size_y ? map.at(ix, iy)
                                                                    : std::numeric_limits<float>::quiet_NaN();
  };
  std::mt19937_64 random(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double half = (options.size - 1) / 2.0;
  // The map's image frame: column ix, row size_y - 1 - iy (row 0 at the highest y).
  const auto centre_mm = [&](const Eigen::Vector2d& top_left) {
    return Eigen::Vector2d(map.x0_mm + (top_left.x() + half) * map.dx_mm,
                           map.y0_mm + (map.size_y - 1 - (top_left.y() + half)) * map.dy_mm);
  };
  for (int col = 0; col < cols; ++col) {
    for (int row = 0; row < rows; ++row) {
      const Eigen::Vector2d nominal(col * step, row * step);
      Eigen::Vector2d error = Eigen::Vector2d::Zero();
      if (!out.tiles.empty()) {
        error = (options.position_sigma_px * Eigen::Vector2d(normal(random), normal(random))).array().round();
        error = error.cwiseMax(-border).cwiseMin(border);
      }
      const Eigen::Vector2i at = (nominal + error).cast<int>() + Eigen::Vector2i::Constant(border);
      imaging::TileImage image(options.size, options.size);
      for (int r = 0; r < options.size; ++r) {
        for (int c = 0; c < options.size; ++c) {
          image(r, c) = height(at.x() + c, map.size_y - 1 - (at.y() + r)) +
                        static_cast<float>(options.noise_mm * normal(random));
        }
      }
      out.images.push_back(std::move(image));
      out.tiles.push_back({row, col, nominal});
      out.truth_px.push_back(nominal + error);
      out.nominal_centre_mm.push_back(centre_mm(nominal + Eigen::Vector2d::Constant(border)));
    }
  }
  return out;
}

}  // namespace fvm::artefacts
