#include "artefacts/simulation/rendered_stitching_strategy.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "artefacts/simulation/calotte_surface.h"
#include "imaging/calotte_detection.h"

namespace fvm::artefacts {
namespace {

// Where the sphere fit puts a calotte that sits exactly at the centre of its tile, less where it is: the fit's
// error in a height map rendered at the tile's pixel size with the lens' height noise.
Eigen::Vector3d CalotteFitError(const RenderedStrategyOptions& options, double pixel_mm, std::uint64_t seed) {
  CalotteSurfaceOptions surface;
  surface.dx_mm = surface.dy_mm = pixel_mm;
  surface.margin_mm = std::max(0.0, options.geometry.fov_mm / 2 - options.calotte_radius_mm);
  surface.noise_sigma_mm = options.height_noise_mm;
  surface.seed = seed;
  const CalotteSurface map = RenderCalotteSurface(SingleCalotte(options.calotte_radius_mm), surface);
  const imaging::CalotteDetection found = imaging::DetectCalottes(map.map);
  if (found.calottes.size() != 1) {
    throw std::runtime_error("rendered strategies: the calotte was not found in its tile; check the radius against "
                             "the field of view");
  }
  return found.calottes.front().fit.centre_mm - map.truth.front().centre;
}

}  // namespace

void RenderedStrategyOptions::Check() const {
  geometry.Check();
  camera.Check();
  registration.Check();
  if (tile_px < 64) throw std::invalid_argument("rendered strategies: tiles of at least 64 px");
  if (!(calotte_radius_mm > 0 && 2 * calotte_radius_mm < geometry.fov_mm)) {
    throw std::invalid_argument("rendered strategies: the calotte must fit in the field of view");
  }
  if (!(height_noise_mm >= 0)) throw std::invalid_argument("rendered strategies: height noise >= 0");
}

RenderedStrategies SimulateRenderedStrategies(const stage::ParameterLayout& layout, const std::vector<double>& values,
                                              const Eigen::Vector3d& first, const Eigen::Vector3d& last,
                                              const RenderedStrategyOptions& options) {
  options.Check();
  const StrategyRow row = PlanStrategyRow(layout, values, first, last, options.geometry);
  const std::vector<StrategyResult> coordinates = SimulateStitchingStrategies(row);
  const int n = static_cast<int>(row.centres.size());
  RenderedStrategies out;
  out.row_tiles = n;
  const double s = out.pixel_mm = options.geometry.fov_mm / options.tile_px;
  const double half = options.geometry.fov_mm / 2;

  // The part's pixel frame: x = X / s, y = -Y / s (image rows run to -Y). Tile i shows the part around where the
  // stage really is, its true centre; the encoders say it is at its command.
  std::mt19937_64 random(options.seed);
  const TileScene scene(options.camera, random);
  std::vector<imaging::TileImage> images;
  std::vector<Eigen::Vector2d> true_px, encoder_px;  // top-left corners, in the part's frame and by the encoders
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& c = row.centres[static_cast<size_t>(i)];
    const Eigen::Vector3d& q = row.commands[static_cast<size_t>(i)];
    true_px.emplace_back((c.x() - half) / s + 0.5, -(c.y() + half) / s + 0.5);
    encoder_px.emplace_back((q.x() - half) / s + 0.5, -(q.y() + half) / s + 0.5);
    images.push_back(scene.Photograph(true_px.back(), options.tile_px, options.tile_px, random));
    out.encoder_centres_mm.push_back(q.head<2>());
  }
  // Every neighbour pair once; each case uses those whose two tiles it takes.
  std::vector<imaging::PairRegistration> neighbours;
  double sum = 0.0;
  int accepted = 0;
  for (int i = 0; i + 1 < n; ++i) {
    const auto a = static_cast<size_t>(i), b = a + 1;
    imaging::PairRegistration pair =
        imaging::RegisterPair(images[a], images[b], encoder_px[b] - encoder_px[a], options.registration);
    pair.a = i;
    pair.b = i + 1;
    if (pair.accepted) {
      sum += (pair.offset_px - (true_px[b] - true_px[a])).squaredNorm();
      ++accepted;
    }
    neighbours.push_back(pair);
  }
  out.rejected_pairs = n - 1 - accepted;
  out.pair_rms_px = accepted > 0 ? std::sqrt(sum / accepted) : 0.0;

  const Eigen::Vector3d fit_first = CalotteFitError(options, s, options.seed + 1);
  const Eigen::Vector3d fit_last = CalotteFitError(options, s, options.seed + 2);
  const std::vector<StrategyCase> cases = StitchingStrategyCases(n);
  for (size_t k = 0; k < cases.size(); ++k) {
    const StrategyCase& c = cases[k];
    // The taken tiles in scan order, renumbered for the solve; the first tile is the origin of the positions.
    std::vector<int> taken, index(static_cast<size_t>(n), -1);
    std::vector<Eigen::Vector2d> nominal;
    for (int i = 0; i < n; ++i) {
      if (c.missing.contains(i)) continue;
      index[static_cast<size_t>(i)] = static_cast<int>(taken.size());
      taken.push_back(i);
      nominal.push_back(encoder_px[static_cast<size_t>(i)] - encoder_px[0]);
    }
    RenderedStrategyResult r;
    std::vector<imaging::PairRegistration> pairs;
    for (imaging::PairRegistration pair : neighbours) {
      if (index[static_cast<size_t>(pair.a)] < 0 || index[static_cast<size_t>(pair.b)] < 0) continue;
      ++r.pairs;
      r.accepted_pairs += pair.accepted;
      pair.a = index[static_cast<size_t>(pair.a)];
      pair.b = index[static_cast<size_t>(pair.b)];
      pairs.push_back(pair);
    }
    const imaging::TilePositions solved =
        imaging::SolveTilePositions(nominal, pairs, options.registration.stage_sigma_px);
    // A tile's centre as the instrument reports it: the first tile's encoder reading plus the solved shift in
    // x and y; its height from the encoder of the tile its chain starts from.
    const auto reported = [&](int t) {
      const size_t j = static_cast<size_t>(t);
      const size_t anchor = static_cast<size_t>(taken[static_cast<size_t>(solved.anchor[j])]);
      const Eigen::Vector2d shift = (solved.positions_px[j] - nominal[0]) * s;
      const size_t i = static_cast<size_t>(taken[j]);
      return Eigen::Vector3d(row.commands[0].x() + shift.x(), row.commands[0].y() - shift.y(),
                             row.centres[i].z() + row.commands[anchor].z() - row.centres[anchor].z());
    };
    r.result.id = c.id;
    r.result.description = c.description;
    r.result.tiles = static_cast<int>(taken.size());
    for (size_t j = 0; j < taken.size(); ++j) {
      if (solved.anchor[j] == static_cast<int>(j)) r.result.encoder_tiles.push_back(taken[j]);
    }
    const Eigen::Vector3d a = reported(0) + fit_first;
    const Eigen::Vector3d b = reported(static_cast<int>(taken.size()) - 1) + fit_last;
    r.result.distance_mm = (b - a).norm();
    r.result.distance_error_um = (r.result.distance_mm - (last - first).norm()) * 1e3;
    r.coordinates = coordinates[k];
    out.cases.push_back(std::move(r));
  }
  out.images = std::move(images);
  return out;
}

}  // namespace fvm::artefacts
