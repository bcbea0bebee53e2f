#include "artefacts/simulation/raw_export_simulation.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "artefacts/simulation/calotte_surface.h"

namespace fvm::artefacts {
namespace {

imaging::HeightMap Render(const std::vector<int>& ids, const std::vector<Eigen::Vector3d>& centres,
                          const RawExportSimulationOptions& options, std::uint64_t seed, const std::string& what) {
  Artefact placed{"bar17", {}};
  for (size_t i = 0; i < centres.size(); ++i) placed.calottes.push_back({ids[i], centres[i], options.radius_mm});
  // The face: the bar's top, rising along the bar as the centres do (least squares), level across it (a plane
  // through centres that lie on one line would take any cross slope).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : centres) mean += c / static_cast<double>(centres.size());
  const Eigen::Vector2d along = centres.size() > 1 ? Eigen::Vector2d((centres.back() - centres.front()).head<2>().normalized())
                                                   : Eigen::Vector2d::UnitX();
  double tt = 0, tz = 0;
  for (const Eigen::Vector3d& c : centres) {
    const double t = (c - mean).head<2>().dot(along);
    tt += t * t;
    tz += t * (c.z() - mean.z());
  }
  const double rise = tt > 0 ? tz / tt : 0.0;  // dz per mm along the bar
  CalotteSurfaceOptions surface;
  surface.dx_mm = surface.dy_mm = options.pixel_mm;
  surface.margin_mm = options.margin_mm;
  surface.slope_x = rise * along.x();
  surface.slope_y = rise * along.y();
  surface.z0_mm = mean.z() - surface.slope_x * mean.x() - surface.slope_y * mean.y();
  surface.centres_as_given = true;
  surface.noise_sigma_mm = options.noise_um * 1e-3;
  surface.seed = seed;
  imaging::HeightMap map = RenderCalotteSurface(placed, surface).map;
  // Only the face within the margin of a rim holds points: a bar across the stage is a narrow band of its map,
  // and stitching-free tiles see only their calotte's neighbourhood.
  const double keep = options.radius_mm + options.margin_mm;
  std::vector<bool> near(map.z_mm.size(), false);
  for (const Eigen::Vector3d& c : centres) {
    const int ix0 = std::max(0, static_cast<int>(std::floor((c.x() - keep - map.x0_mm) / map.dx_mm)));
    const int ix1 = std::min(map.size_x - 1, static_cast<int>(std::ceil((c.x() + keep - map.x0_mm) / map.dx_mm)));
    const int iy0 = std::max(0, static_cast<int>(std::floor((c.y() - keep - map.y0_mm) / map.dy_mm)));
    const int iy1 = std::min(map.size_y - 1, static_cast<int>(std::ceil((c.y() + keep - map.y0_mm) / map.dy_mm)));
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        const double x = map.x0_mm + ix * map.dx_mm - c.x(), y = map.y0_mm + iy * map.dy_mm - c.y();
        if (x * x + y * y <= keep * keep) near[static_cast<size_t>(iy) * static_cast<size_t>(map.size_x) + ix] = true;
      }
    }
  }
  for (size_t i = 0; i < near.size(); ++i) {
    if (!near[i]) map.z_mm[i] = std::numeric_limits<double>::quiet_NaN();
  }
  map.source = "fvm simulate fvm-batch --surfaces: " + what;
  return map;
}

}  // namespace

void RawExportSimulationOptions::Check() const {
  if (!(pixel_mm > 0) || !(noise_um >= 0) || !(margin_mm >= 0) || !(radius_mm > 0) || !std::isfinite(pixel_mm) ||
      !std::isfinite(noise_um) || !std::isfinite(margin_mm) || !std::isfinite(radius_mm)) {
    throw std::invalid_argument("raw exports: pixel and radius must be > 0, noise and margin >= 0");
  }
}

RawExportPair RenderRawExports(const Placement& placement, std::size_t index, const RawExportSimulationOptions& options) {
  options.Check();
  // SplitMix64-like spreading: neighbouring placements and the two exports get unrelated streams.
  const std::uint64_t base = (options.seed + 0x9e3779b97f4a7c15ULL * (2 * index + 1)) * 0xbf58476d1ce4e5b9ULL;
  return {Render(placement.ids, placement.stitched, options, base ^ 0x1ULL, placement.name + " stitched"),
          Render(placement.ids, placement.free, options, base ^ 0x2ULL, placement.name + " stitching-free")};
}

}  // namespace fvm::artefacts
