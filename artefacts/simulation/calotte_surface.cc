#include "artefacts/simulation/calotte_surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace fvm::artefacts {
namespace {

enum PixelState : std::uint8_t { kFace = 0, kDimple = 1, kTooSteep = 2 };

struct PlacedCalotte {
  int id;
  Eigen::Vector3d centre;  // true sphere centre in map coordinates
  double radius;
  double opening;  // radius of the rim circle in the face
};

// The calottes where the options put them, the face they are cut into, and the region they span with the margin.
struct Scene {
  std::vector<PlacedCalotte> placed;
  Eigen::Vector2d lo, hi;
  double z0, slope_x, slope_y;
  double FaceZ(double x, double y) const { return z0 + slope_x * x + slope_y * y; }
};

Scene PlaceCalottes(const Artefact& artefact, const CalotteSurfaceOptions& options) {
  options.Check();
  if (artefact.calottes.empty()) throw std::invalid_argument("height map: the artefact has no calottes");
  const Eigen::Rotation2Dd turn(options.rotation_rad);
  Scene scene;
  scene.z0 = options.z0_mm;
  scene.slope_x = options.slope_x;
  scene.slope_y = options.slope_y;
  const auto face_z = [&](double x, double y) { return scene.FaceZ(x, y); };
  const Eigen::Vector3d normal = Eigen::Vector3d(-options.slope_x, -options.slope_y, 1.0).normalized();
  std::vector<PlacedCalotte>& placed = scene.placed;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Calotte& c : artefact.calottes) {
    const double depth = options.depth_mm > 0 ? options.depth_mm : c.radius_mm;
    if (!(c.radius_mm > 0) || depth > c.radius_mm * (1 + 1e-12)) {
      throw std::invalid_argument("height map: calotte " + std::to_string(c.id) +
                                  ": depth must not exceed the radius (an undercut hole is invisible from above)");
    }
    const Eigen::Vector2d xy = turn * c.centre.head<2>() + options.offset_mm;
    // The sphere's centre sits (radius - depth) above the face, along the face's normal.
    double above = c.radius_mm - std::min(depth, c.radius_mm);
    Eigen::Vector3d centre = Eigen::Vector3d(xy.x(), xy.y(), face_z(xy.x(), xy.y())) + above * normal;
    if (options.centres_as_given) {
      centre = Eigen::Vector3d(xy.x(), xy.y(), c.centre.z());
      above = std::clamp((c.centre.z() - face_z(xy.x(), xy.y())) * normal.z(), -c.radius_mm, c.radius_mm);
    }
    placed.push_back({c.id, centre, c.radius_mm, std::sqrt(c.radius_mm * c.radius_mm - above * above)});
    const double reach = c.radius_mm + 6 * options.burr_width_mm;
    const Eigen::Vector2d span = Eigen::Vector2d::Constant(reach + options.margin_mm);
    lo = lo.cwiseMin(xy - span);
    hi = hi.cwiseMax(xy + span);
  }
  scene.lo = lo;
  scene.hi = hi;
  return scene;
}

// The first surface seen from +z at (x, y) of one calotte's neighbourhood: the ball's lower half when the vertical
// line meets the hole (too steep for the optics beyond max_slope), else the face with the calotte's burr.
void FirstSurface(const PlacedCalotte& c, const Scene& scene, const CalotteSurfaceOptions& options, double min_cos,
                  double x, double y, double* z, std::uint8_t* state) {
  const double rho2 = (x - c.centre.x()) * (x - c.centre.x()) + (y - c.centre.y()) * (y - c.centre.y());
  const double face = scene.FaceZ(x, y);
  if (rho2 < c.radius * c.radius) {
    const double s = std::sqrt(c.radius * c.radius - rho2);
    // The vertical line meets the hole when it enters the ball below the face and leaves it above: then
    // the first surface from above is the ball's lower half.
    if (c.centre.z() - s < face && c.centre.z() + s >= face) {
      *z = c.centre.z() - s;
      *state = s / c.radius < min_cos ? kTooSteep : kDimple;
      return;
    }
  }
  if (*state == kFace && options.burr_height_mm > 0) {
    const double beyond = (std::sqrt(rho2) - c.opening) / options.burr_width_mm;
    if (beyond >= 0) *z += options.burr_height_mm * std::exp(-0.5 * beyond * beyond);
  }
}

}  // namespace

void CalotteSurfaceOptions::Check() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  const auto fraction = [](double v) { return v >= 0 && v < 1; };
  if (!positive(dx_mm) || !positive(dy_mm)) throw std::invalid_argument("height map: pixel size must be positive");
  if (!(margin_mm >= 0) || !(depth_mm >= 0) || !(noise_sigma_mm >= 0) || !(spike_height_mm >= 0) ||
      !(burr_height_mm >= 0) || !positive(burr_width_mm)) {
    throw std::invalid_argument("height map: margin, depth, noise, spike and burr sizes must be non-negative");
  }
  if (!(max_slope_deg > 0 && max_slope_deg <= 90)) {
    throw std::invalid_argument("height map: the largest measurable slope must be in (0, 90] degrees");
  }
  if (!fraction(missing_fraction) || !fraction(spike_fraction)) {
    throw std::invalid_argument("height map: missing and spike fractions must be in [0, 1)");
  }
  if (!std::isfinite(rotation_rad) || !offset_mm.allFinite() || !std::isfinite(z0_mm) || !std::isfinite(slope_x) ||
      !std::isfinite(slope_y)) {
    throw std::invalid_argument("height map: placement and plane must be finite");
  }
}

Artefact SingleCalotte(double radius_mm) {
  return Artefact{"calotte", {Calotte{1, Eigen::Vector3d::Zero(), radius_mm}}};
}

CalotteSurface RenderCalotteSurface(const Artefact& artefact, const CalotteSurfaceOptions& options) {
  const Scene scene = PlaceCalottes(artefact, options);
  const std::vector<PlacedCalotte>& placed = scene.placed;
  const Eigen::Vector2d& lo = scene.lo;
  const Eigen::Vector2d& hi = scene.hi;
  const auto face_z = [&](double x, double y) { return scene.FaceZ(x, y); };

  CalotteSurface out;
  imaging::HeightMap& map = out.map;
  map.dx_mm = options.dx_mm;
  map.dy_mm = options.dy_mm;
  map.x0_mm = lo.x();
  map.y0_mm = lo.y();
  const double nx = std::floor((hi.x() - lo.x()) / options.dx_mm) + 1;
  const double ny = std::floor((hi.y() - lo.y()) / options.dy_mm) + 1;
  if (nx * ny > 4e8) throw std::invalid_argument("height map: more than 400 million points; use larger pixels");
  map.size_x = static_cast<int>(nx);
  map.size_y = static_cast<int>(ny);
  map.source = "rendered " + artefact.name;
  map.z_mm.resize(static_cast<size_t>(map.size_x) * static_cast<size_t>(map.size_y));

  // Heights in double, as the map holds them.
  std::vector<double> z(map.z_mm.size());
  std::vector<std::uint8_t> state(map.z_mm.size(), kFace);
  const auto index = [&](int ix, int iy) { return static_cast<size_t>(iy) * static_cast<size_t>(map.size_x) + ix; };
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix)
      z[index(ix, iy)] = face_z(map.x0_mm + ix * map.dx_mm, map.y0_mm + iy * map.dy_mm);
  }
  const double min_cos = std::cos(options.max_slope_deg * M_PI / 180.0);
  for (const PlacedCalotte& c : placed) {
    const double reach = c.radius + 6 * options.burr_width_mm;
    const int ix0 = std::max(0, static_cast<int>(std::floor((c.centre.x() - reach - map.x0_mm) / map.dx_mm)));
    const int ix1 =
        std::min(map.size_x - 1, static_cast<int>(std::ceil((c.centre.x() + reach - map.x0_mm) / map.dx_mm)));
    const int iy0 = std::max(0, static_cast<int>(std::floor((c.centre.y() - reach - map.y0_mm) / map.dy_mm)));
    const int iy1 =
        std::min(map.size_y - 1, static_cast<int>(std::ceil((c.centre.y() + reach - map.y0_mm) / map.dy_mm)));
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        const size_t i = index(ix, iy);
        FirstSurface(c, scene, options, min_cos, map.x0_mm + ix * map.dx_mm, map.y0_mm + iy * map.dy_mm, &z[i], &state[i]);
      }
    }
  }

  // Each effect draws from its own generator, so switching one on leaves the others' draws as they were.
  std::mt19937_64 noise_rng(options.seed);
  std::mt19937_64 missing_rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::mt19937_64 spike_rng(options.seed ^ 0xc2b2ae3d27d4eb4fULL);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (size_t i = 0; i < z.size(); ++i) {
    double v = z[i];
    if (options.noise_sigma_mm > 0) v += options.noise_sigma_mm * noise(noise_rng);
    if (options.spike_fraction > 0 && uniform(spike_rng) < options.spike_fraction) {
      v += options.spike_height_mm * (2 * uniform(spike_rng) - 1);
    }
    const bool missing = options.missing_fraction > 0 && uniform(missing_rng) < options.missing_fraction;
    map.z_mm[i] = state[i] == kTooSteep || missing ? std::numeric_limits<double>::quiet_NaN() : v;
  }

  for (const PlacedCalotte& c : placed) out.truth.push_back(Calotte{c.id, c.centre, c.radius});
  return out;
}

}  // namespace fvm::artefacts

namespace fvm::artefacts {

CalotteCloud RenderCalotteCloud(const Artefact& artefact, const CalotteSurfaceOptions& options, std::size_t points) {
  const Scene scene = PlaceCalottes(artefact, options);
  const double min_cos = std::cos(options.max_slope_deg * M_PI / 180.0);
  std::mt19937_64 place_rng(options.seed ^ 0x94d049bb133111ebULL);
  std::mt19937_64 noise_rng(options.seed);
  std::mt19937_64 missing_rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::mt19937_64 spike_rng(options.seed ^ 0xc2b2ae3d27d4eb4fULL);
  std::uniform_real_distribution<double> along_x(scene.lo.x(), scene.hi.x()), along_y(scene.lo.y(), scene.hi.y());
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  CalotteCloud out;
  std::vector<Eigen::Vector3d> cloud;
  cloud.reserve(points);
  for (std::size_t k = 0; k < points; ++k) {
    const double x = along_x(place_rng), y = along_y(place_rng);
    double z = scene.FaceZ(x, y);
    std::uint8_t state = kFace;
    for (const PlacedCalotte& c : scene.placed) {
      if (std::abs(x - c.centre.x()) > c.radius + 6 * options.burr_width_mm ||
          std::abs(y - c.centre.y()) > c.radius + 6 * options.burr_width_mm) {
        continue;
      }
      FirstSurface(c, scene, options, min_cos, x, y, &z, &state);
    }
    if (options.noise_sigma_mm > 0) z += options.noise_sigma_mm * noise(noise_rng);
    if (options.spike_fraction > 0 && uniform(spike_rng) < options.spike_fraction) {
      z += options.spike_height_mm * (2 * uniform(spike_rng) - 1);
    }
    const bool missing = options.missing_fraction > 0 && uniform(missing_rng) < options.missing_fraction;
    if (state == kTooSteep || missing) continue;  // a cloud leaves out what the instrument did not measure
    cloud.emplace_back(x, y, z);
  }
  out.cloud = imaging::MakeUnorganisedCloud(std::move(cloud));
  out.cloud.source = "rendered " + artefact.name + " (unorganised)";
  for (const PlacedCalotte& c : scene.placed) out.truth.push_back(Calotte{c.id, c.centre, c.radius});
  return out;
}

}  // namespace fvm::artefacts
