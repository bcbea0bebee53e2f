#include "artefacts/simulation/tile_synthesis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fvm::artefacts {

void TileCameraOptions::Check() const {
  if (components < 1 || !(max_frequency > 0.0 && max_frequency <= 0.5)) {
    throw std::invalid_argument("tiles: components >= 1, max frequency in (0, 0.5]");
  }
  if (!(wave_spread_deg >= 0.0 && wave_spread_deg <= 360.0)) throw std::invalid_argument("tiles: spread in [0, 360]");
  if (!(vignetting >= 0.0 && vignetting < 1.0) || !(noise >= 0.0) || !(contrast >= 0.0) || !(electrons_per_count >= 0.0)) {
    throw std::invalid_argument("tiles: vignetting in [0, 1), noise and contrast >= 0");
  }
}

void TileSynthesisOptions::Check() const {
  if (rows < 1 || cols < 1 || width < 16 || height < 16) throw std::invalid_argument("tiles: at least 1 x 1 of 16 px");
  if (!(overlap > 0.0 && overlap < 1.0)) throw std::invalid_argument("tiles: overlap in (0, 1)");
  if (!(position_sigma_px >= 0.0)) throw std::invalid_argument("tiles: position sigma >= 0");
  camera.Check();
}

TileScene::TileScene(const TileCameraOptions& options, std::mt19937_64& random) : options_(options) {
  options.Check();
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  double power = 0.0;
  for (int k = 0; k < options.components; ++k) {
    // Frequencies from a tenth of the maximum up: slower waves would look like illumination, not texture.
    const double f = options.max_frequency * (0.1 + 0.9 * uniform(random));
    const double angle = (options.wave_angle_deg + options.wave_spread_deg * uniform(random)) * std::numbers::pi / 180;
    waves_.push_back({f * std::cos(angle), f * std::sin(angle), 2.0 * std::numbers::pi * uniform(random), 1.0 / f});
    power += 0.5 / (f * f);
  }
  const double scale = options.contrast / std::sqrt(power);
  for (Wave& w : waves_) w.amplitude *= scale;
}

imaging::TileImage TileScene::Photograph(const Eigen::Vector2d& top_left_px, int width, int height,
                                         std::mt19937_64& random) const {
  return Photograph(Eigen::Matrix2d::Identity(), top_left_px, width, height, random);
}

imaging::TileImage TileScene::Photograph(const Eigen::Matrix2d& axes, const Eigen::Vector2d& origin_px, int width,
                                         int height, std::mt19937_64& random) const {
  // A wave's phase at pixel (x, y) is a x + b y + c under an affine map, and sin(a x + (b y + c)) = sin(a x)
  // cos(b y + c) + cos(a x) sin(b y + c): each wave is a rank-2 outer product of a column and a row factor, so a
  // tile costs two multiply-adds per pixel and wave, and sin/cos only per row and column. Row-major so that each
  // row update below is one contiguous, vectorised pass.
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMajor texture = RowMajor::Zero(height, width);
  Eigen::VectorXd sy(height), cy(height);
  Eigen::RowVectorXd sx(width), cx(width);
  for (const Wave& w : waves_) {
    const Eigen::Vector2d f = 2.0 * std::numbers::pi * Eigen::Vector2d(w.fx, w.fy);
    const double along_x = f.dot(axes.col(0)), along_y = f.dot(axes.col(1)), offset = f.dot(origin_px) + w.phase;
    for (int y = 0; y < height; ++y) {
      const double b = along_y * y + offset;
      sy(y) = std::sin(b);
      cy(y) = std::cos(b);
    }
    for (int x = 0; x < width; ++x) {
      const double a = along_x * x;
      sx(x) = std::sin(a);
      cx(x) = std::cos(a);
    }
    for (int y = 0; y < height; ++y) texture.row(y) += (w.amplitude * cy(y)) * sx + (w.amplitude * sy(y)) * cx;
  }
  std::normal_distribution<double> normal(0.0, 1.0);
  imaging::TileImage image(height, width);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double u = (x + 0.5) / width - 0.5, v = (y + 0.5) / height - 0.5;
      const double gain = 1.0 - options_.vignetting * 2.0 * (u * u + v * v);  // 2 (u^2 + v^2) = 1 at corners
      double t = texture(y, x);
      if (options_.blobs) {
        const double crest = std::max(0.0, t / options_.contrast - 1.5);
        t = 4.0 * options_.contrast * crest * crest;
      }
      const double counts = gain * (options_.level + t);
      double sigma = options_.noise * options_.contrast;
      if (options_.electrons_per_count > 0.0) sigma = std::hypot(sigma, std::sqrt(std::max(counts, 0.0) / options_.electrons_per_count));
      image(y, x) = static_cast<float>(counts + sigma * normal(random));
    }
  }
  return image;
}

SynthesizedTiles SynthesizeTiles(const TileSynthesisOptions& options) {
  options.Check();
  std::mt19937_64 random(options.seed);
  SynthesizedTiles out;
  out.scene = TileScene(options.camera, random);
  const TileScene& scene = out.scene;
  std::normal_distribution<double> normal(0.0, 1.0);
  const double step_x = options.width * (1.0 - options.overlap), step_y = options.height * (1.0 - options.overlap);
  for (int col = 0; col < options.cols; ++col) {
    for (int row = 0; row < options.rows; ++row) {
      const Eigen::Vector2d nominal(col * step_x, row * step_y);
      Eigen::Vector2d truth = nominal;
      if (!out.tiles.empty()) truth += options.position_sigma_px * Eigen::Vector2d(normal(random), normal(random));
      out.tiles.push_back({row, col, nominal});
      out.truth_px.push_back(truth);
      out.images.push_back(scene.Photograph(truth, options.width, options.height, random));
    }
  }
  return out;
}

}  // namespace fvm::artefacts
