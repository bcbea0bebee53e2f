#pragma once
// Height maps of calotte artefacts with a recorded truth: what a focus-variation instrument would export when
// it looks at the artefact from above. Each calotte is a spherical dimple cut into a (possibly tilted) plane;
// the map holds, at every pixel centre, the exact height of the first surface seen from +z, then Gaussian
// height noise, dropouts (NaN) where the flank is too steep for the optics and at random, spikes and burrs.
// The truth is the sphere of every calotte in map coordinates (mm).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "imaging/height_map.h"
#include "imaging/point_cloud.h"

namespace fvm::artefacts {

struct CalotteSurfaceOptions {
  double dx_mm = 0.01;  // pixel pitch; the map's x0_mm, y0_mm place it so that the calottes sit inside
  double dy_mm = 0.01;
  double margin_mm = 1.0;  // flat border beyond the outermost calotte rims
  // Placement: the artefact's frame is turned by rotation_rad about z, then shifted by offset_mm, so that a
  // nominal calotte centre (x, y) lands at R (x, y) + offset in the map.
  double rotation_rad = 0.0;
  Eigen::Vector2d offset_mm = Eigen::Vector2d::Zero();
  // The top face: z = z0 + slope_x x + slope_y y (a tilted plane; the calottes tilt with it, as a rigid part).
  double z0_mm = 0.0;
  double slope_x = 0.0;
  double slope_y = 0.0;
  // Depth of each dimple below the face along the face's normal; 0 means a hemisphere (depth = radius, the
  // sphere's centre in the face), as the calotte grid of [Pérez 2019] (section 1.2).
  double depth_mm = 0.0;
  // The sphere centres are the artefact's own (x, y, z) after the placement, each a little above or below the face
  // as the calottes of a real part are: the face then only decides where the hole opens (depth_mm is unused).
  bool centres_as_given = false;
  // The optics see no steeper flank: those points come out invalid (NaN), as real exports have a ring of
  // missing points inside the rim of a deep calotte.
  double max_slope_deg = 75.0;
  double noise_sigma_mm = 0.0;    // Gaussian height noise, independent per pixel
  double missing_fraction = 0.0;  // share of the remaining points dropped at random
  double spike_fraction = 0.0;    // share of points with a gross height error, uniform in +-spike_height_mm
  double spike_height_mm = 0.01;
  double burr_height_mm = 0.0;  // a raised lip just outside each rim (milling burr), Gaussian in profile
  double burr_width_mm = 0.01;
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct CalotteSurface {
  imaging::HeightMap map;
  std::vector<Calotte> truth;  // id, true sphere centre in map coordinates (mm), sphere radius
};

CalotteSurface RenderCalotteSurface(const Artefact& artefact, const CalotteSurfaceOptions& options);

// The same surface as an unorganised cloud, as form-measurement exports hold it: `points` places drawn uniformly
// over the region the map would cover (seeded), each with the first surface's height there, the same noise, spikes
// and dropouts; points on flanks steeper than max_slope_deg are left out (the cloud has no NaN). Truth as above.
struct CalotteCloud {
  imaging::PointCloud cloud;
  std::vector<Calotte> truth;
};
CalotteCloud RenderCalotteCloud(const Artefact& artefact, const CalotteSurfaceOptions& options, std::size_t points);

// One calotte of the given radius with its centre's nominal position at the artefact origin (id 1).
Artefact SingleCalotte(double radius_mm);

}  // namespace fvm::artefacts
