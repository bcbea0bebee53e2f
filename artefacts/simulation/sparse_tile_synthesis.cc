#include "artefacts/simulation/sparse_tile_synthesis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace fvm::artefacts {
namespace {

struct Blob {
  Eigen::Vector2d centre;  // in the frame of tile 0's top-left corner (px)
  double sigma, peak;
};

// The sample's reflectance varies slowly: two waves of periods of 2-4 tiles, fixed to the sample.
struct Background {
  double level = 0.0, variation = 0.0;
  Eigen::Vector2d k1, k2;
  double phase1 = 0.0, phase2 = 0.0;
  double At(const Eigen::Vector2d& p) const {
    return level * (1.0 + 0.5 * variation * (std::sin(k1.dot(p) + phase1) + std::sin(k2.dot(p) + phase2)));
  }
};

}  // namespace

void SparseTileOptions::Check() const {
  if (rows < 1 || cols < 1 || width < 16 || height < 16) throw std::invalid_argument("tiles: at least 1 x 1 of 16 px");
  if (!(overlap > 0.0 && overlap < 1.0)) throw std::invalid_argument("tiles: overlap in (0, 1)");
  if (!(repeatability_px >= 0.0)) throw std::invalid_argument("tiles: repeatability >= 0");
  if (!(blobs_per_kpx2 > 0.0) || !(blob_sigma_min_px > 0.0 && blob_sigma_max_px >= blob_sigma_min_px) ||
      !(blob_peak_min > 0.0 && blob_peak_max >= blob_peak_min)) {
    throw std::invalid_argument("tiles: blob density, sizes and peaks must be positive, min <= max");
  }
  if (!(background >= 0.0 && background_variation >= 0.0 && background_variation < 1.0) ||
      !(vignetting >= 0.0 && vignetting < 1.0) || !(electrons_per_count > 0.0 && read_noise >= 0.0)) {
    throw std::invalid_argument("tiles: background >= 0, variation and vignetting in [0, 1), gain > 0, read noise >= 0");
  }
}

SynthesizedTiles SynthesizeSparseTiles(const SparseTileOptions& options) {
  options.Check();
  std::mt19937_64 random(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  SynthesizedTiles out;
  const Eigen::Vector2d east(options.width * (1.0 - options.overlap), 0.0);
  const Eigen::Vector2d south(0.0, options.height * (1.0 - options.overlap));
  const Eigen::Vector2d true_east = east + options.east_step_error_px;
  const Eigen::Vector2d true_south = south + options.south_step_error_px;
  for (int col = 0; col < options.cols; ++col) {
    for (int row = 0; row < options.rows; ++row) {
      Eigen::Vector2d truth = col * true_east + row * true_south;
      if (!out.tiles.empty()) truth += options.repeatability_px * Eigen::Vector2d(normal(random), normal(random));
      out.tiles.push_back({row, col, col * east + row * south});
      out.truth_px.push_back(truth);
    }
  }
  // Blobs over the area all tiles cover, with a margin for the widest blob.
  Eigen::Vector2d low = out.truth_px.front(), high = low;
  for (const auto& p : out.truth_px) low = low.cwiseMin(p), high = high.cwiseMax(p);
  const double margin = 4.0 * options.blob_sigma_max_px;
  low.array() -= margin;
  high += Eigen::Vector2d(options.width + margin, options.height + margin);
  const Eigen::Vector2d extent = high - low;
  const auto count = static_cast<int>(std::lround(options.blobs_per_kpx2 * extent.prod() / 1000.0));
  std::vector<Blob> blobs;
  const double log_ratio = std::log(options.blob_peak_max / options.blob_peak_min);
  for (int k = 0; k < count; ++k) {
    Blob b;
    b.centre = low + Eigen::Vector2d(uniform(random) * extent.x(), uniform(random) * extent.y());
    b.sigma = options.blob_sigma_min_px + (options.blob_sigma_max_px - options.blob_sigma_min_px) * uniform(random);
    b.peak = options.blob_peak_min * std::exp(log_ratio * uniform(random));
    blobs.push_back(b);
  }
  Background background;
  background.level = options.background;
  background.variation = options.background_variation;
  const double tile = std::max(options.width, options.height);
  for (Eigen::Vector2d* k : {&background.k1, &background.k2}) {
    const double angle = 2.0 * std::numbers::pi * uniform(random);
    const double period = tile * (2.0 + 2.0 * uniform(random));
    *k = 2.0 * std::numbers::pi / period * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  }
  background.phase1 = 2.0 * std::numbers::pi * uniform(random);
  background.phase2 = 2.0 * std::numbers::pi * uniform(random);

  for (const Eigen::Vector2d& origin : out.truth_px) {
    // The scene at the pixel centres of this tile: background, then every blob that reaches it.
    Eigen::MatrixXd scene(options.height, options.width);
    for (int y = 0; y < options.height; ++y) {
      for (int x = 0; x < options.width; ++x) scene(y, x) = background.At(origin + Eigen::Vector2d(x, y));
    }
    for (const Blob& b : blobs) {
      const Eigen::Vector2d c = b.centre - origin;
      const double reach = 4.0 * b.sigma;
      const int x0 = std::max(0, static_cast<int>(std::floor(c.x() - reach)));
      const int x1 = std::min(options.width - 1, static_cast<int>(std::ceil(c.x() + reach)));
      const int y0 = std::max(0, static_cast<int>(std::floor(c.y() - reach)));
      const int y1 = std::min(options.height - 1, static_cast<int>(std::ceil(c.y() + reach)));
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const double r2 = (Eigen::Vector2d(x, y) - c).squaredNorm();
          scene(y, x) += b.peak * std::exp(-0.5 * r2 / (b.sigma * b.sigma));
        }
      }
    }
    imaging::TileImage image(options.height, options.width);
    for (int y = 0; y < options.height; ++y) {
      for (int x = 0; x < options.width; ++x) {
        const double u = (x + 0.5) / options.width - 0.5, v = (y + 0.5) / options.height - 0.5;
        const double counts = scene(y, x) * (1.0 - options.vignetting * 2.0 * (u * u + v * v));
        const double noisy = counts + std::sqrt(counts / options.electrons_per_count) * normal(random) +
                             options.read_noise * normal(random);
        image(y, x) = static_cast<float>(std::clamp(std::round(noisy), 0.0, 65535.0));
      }
    }
    out.images.push_back(std::move(image));
  }
  return out;
}

}  // namespace fvm::artefacts
