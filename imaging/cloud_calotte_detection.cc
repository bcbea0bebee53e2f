#include "imaging/cloud_calotte_detection.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::imaging {
namespace {

// A cell holding points further apart in z than this, well beyond a microscope's noise and the height change
// across a cell on a 70 degree wall, sees two surfaces: the cloud is not 2.5D there.
constexpr double kOverhangFactor = 6.0;   // times the cell size (tan 80 deg ~ 5.7)
constexpr double kMaxOverhangShare = 0.01;

}  // namespace

CloudCalotteDetection DetectCalottesInCloud(const PointCloud& cloud, const CalotteDetectionOptions& options,
                                            const std::string& name) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.points.size());
  for (const Eigen::Vector3d& p : cloud.points) {
    if (p.allFinite()) points.push_back(p);
  }
  if (points.size() < 100) {
    throw InputError(name + ": " + std::to_string(points.size()) +
                     " valid points; a calotte needs hundreds (NaN and infinite points are skipped)");
  }
  Eigen::Vector2d lo = points.front().head<2>(), hi = lo;
  for (const Eigen::Vector3d& p : points) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  const Eigen::Vector2d span = hi - lo;
  if (!(span.minCoeff() > 0.0)) throw InputError(name + ": the cloud's points lie on a line in x, y; no surface to search");
  // About four points per cell: few empty cells (2 % for a uniform cloud), and a cell still small against a calotte.
  const double cell = 2.0 * std::sqrt(span.x() * span.y() / static_cast<double>(points.size()));
  const double nx = std::floor(span.x() / cell) + 1, ny = std::floor(span.y() / cell) + 1;
  if (nx * ny > 4e8) throw InputError(name + ": the cloud is too sparse for its extent to be projected on a grid");
  HeightMap map;
  map.size_x = static_cast<int>(nx);
  map.size_y = static_cast<int>(ny);
  map.dx_mm = map.dy_mm = cell;
  map.x0_mm = lo.x() + 0.5 * cell;  // cell centres
  map.y0_mm = lo.y() + 0.5 * cell;
  map.source = cloud.source;
  const std::size_t cells = static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y);
  std::vector<double> sum(cells, 0.0), low(cells, std::numeric_limits<double>::infinity()),
      high(cells, -std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> count(cells, 0);
  for (const Eigen::Vector3d& p : points) {
    const int ix = std::min(map.size_x - 1, static_cast<int>((p.x() - lo.x()) / cell));
    const int iy = std::min(map.size_y - 1, static_cast<int>((p.y() - lo.y()) / cell));
    const std::size_t i = static_cast<std::size_t>(iy) * static_cast<std::size_t>(map.size_x) + static_cast<std::size_t>(ix);
    sum[i] += p.z();
    ++count[i];
    low[i] = std::min(low[i], p.z());
    high[i] = std::max(high[i], p.z());
  }
  std::size_t occupied = 0, overhanging = 0;
  map.z_mm.assign(cells, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < cells; ++i) {
    if (count[i] == 0) continue;
    ++occupied;
    if (high[i] - low[i] > kOverhangFactor * cell) ++overhanging;
    map.z_mm[i] = sum[i] / count[i];
  }
  if (static_cast<double>(overhanging) > kMaxOverhangShare * static_cast<double>(occupied)) {
    throw InputError(name + ": not a 2.5D cloud: " + std::to_string(overhanging) + " of its " + std::to_string(occupied) +
                     " grid cells of " + FormatShortest(cell) + " mm hold points " + FormatShortest(kOverhangFactor * cell) +
                     " mm or more apart in z (surfaces above one another); fvm fit finds calottes in clouds seen "
                     "from above, as a microscope measures them: crop the cloud to the face with the calottes");
  }

  CloudCalotteDetection out;
  out.grid_mm = cell;
  out.detection = DetectCalottes(map, options);
  out.method = "grid projection (2.5D cloud: " + std::to_string(points.size()) + " points on " +
               FormatShortest(std::round(cell * 1e7) / 1e4) + " um cells), spheres fitted to the cloud's own points";
  const FacePlane& face = out.detection.face;
  std::vector<DetectedCalotte> kept;
  for (DetectedCalotte& c : out.detection.calottes) {
    // The dimple's own points: deeper than the threshold below the face, inside its outline (the grid's extent
    // and a cell for the cells' width).
    const Eigen::Vector2d middle = c.fit.centre_mm.head<2>();
    const double reach = 0.5 * c.extent_mm.maxCoeff() + cell;
    std::vector<Eigen::Vector3d> dimple;
    for (const Eigen::Vector3d& p : points) {
      if ((p.head<2>() - middle).squaredNorm() > reach * reach) continue;
      if (face.Height(p.x(), p.y()) - p.z() > out.detection.min_depth_mm) dimple.push_back(p);
    }
    try {
      c.fit = FitSphere(dimple, options.fit);
    } catch (const InputError& e) {
      out.detection.rejected.push_back({middle, c.extent_mm, dimple.size(), std::string("no sphere: ") + e.what()});
      continue;
    }
    kept.push_back(std::move(c));
  }
  out.detection.calottes = std::move(kept);
  return out;
}

}  // namespace fvm::imaging
