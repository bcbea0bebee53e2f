#include "imaging/point_cloud.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::imaging {
namespace {

bool IsValid(const Eigen::Vector3d& p) { return p.allFinite(); }

// Least-squares line value = a + b * index over the valid points; returns {a, b, largest residual}.
struct Line {
  double offset = 0.0, slope = 0.0, worst = 0.0;
};

Line FitLine(const std::vector<std::pair<double, double>>& samples) {
  double mean_i = 0.0, mean_v = 0.0;
  for (const auto& [i, v] : samples) mean_i += i, mean_v += v;
  mean_i /= static_cast<double>(samples.size());
  mean_v /= static_cast<double>(samples.size());
  double sii = 0.0, siv = 0.0;
  for (const auto& [i, v] : samples) sii += (i - mean_i) * (i - mean_i), siv += (i - mean_i) * (v - mean_v);
  Line line;
  line.slope = sii > 0.0 ? siv / sii : 0.0;
  line.offset = mean_v - line.slope * mean_i;
  for (const auto& [i, v] : samples) line.worst = std::max(line.worst, std::fabs(v - line.offset - line.slope * i));
  return line;
}

}  // namespace

PointCloud MakeUnorganisedCloud(std::vector<Eigen::Vector3d> points) {
  PointCloud cloud;
  cloud.width = static_cast<int>(points.size());
  cloud.height = points.empty() ? 0 : 1;
  cloud.points = std::move(points);
  return cloud;
}

PointCloud HeightMapToCloud(const HeightMap& map) {
  if (map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y)) {
    throw std::invalid_argument("HeightMapToCloud: the map's point count does not match its size");
  }
  PointCloud cloud;
  cloud.width = map.size_x;
  cloud.height = map.size_y;
  cloud.source = map.source;
  cloud.points.reserve(map.z_mm.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix) {
      const double z = map.at(ix, iy);
      cloud.points.emplace_back(std::isfinite(z)
                                    ? Eigen::Vector3d(map.x0_mm + ix * map.dx_mm, map.y0_mm + iy * map.dy_mm, z)
                                    : Eigen::Vector3d(nan, nan, nan));
    }
  }
  return cloud;
}

HeightMap CloudToHeightMap(const PointCloud& cloud, const std::string& name) {
  if (cloud.width < 1 || cloud.height < 1 ||
      cloud.points.size() != static_cast<std::size_t>(cloud.width) * static_cast<std::size_t>(cloud.height)) {
    throw InputError(name + ": the cloud's " + std::to_string(cloud.points.size()) + " points are not a " +
                     std::to_string(cloud.width) + " x " + std::to_string(cloud.height) + " grid");
  }
  if (!cloud.IsOrganised()) {
    throw InputError(name + ": an unorganised point cloud (one row of " + std::to_string(cloud.width) +
                     " points) has no grid to make a height map of; use an organised cloud or a height-map file");
  }
  std::vector<std::pair<double, double>> xs, ys;
  for (int iy = 0; iy < cloud.height; ++iy) {
    for (int ix = 0; ix < cloud.width; ++ix) {
      const Eigen::Vector3d& p = cloud.points[static_cast<std::size_t>(iy) * cloud.width + ix];
      if (!IsValid(p)) continue;
      xs.emplace_back(ix, p.x());
      ys.emplace_back(iy, p.y());
    }
  }
  const Line x = xs.empty() ? Line{} : FitLine(xs);
  const Line y = ys.empty() ? Line{} : FitLine(ys);
  if (!(x.slope > 0.0) || !(y.slope > 0.0)) {
    throw InputError(name +
                     ": the organised cloud's valid points do not span two columns and two rows with x and y "
                     "increasing, so its grid spacing is unknown; it is not a height map");
  }
  const double tolerance = 0.01 * std::min(x.slope, y.slope);
  if (x.worst > tolerance || y.worst > tolerance) {
    throw InputError(name + ": the organised cloud is not on a regular grid (points are up to " +
                     FormatShortest(std::max(x.worst, y.worst)) + " mm off a grid of " + FormatShortest(x.slope) +
                     " x " + FormatShortest(y.slope) + " mm); it cannot be a height map");
  }
  HeightMap map;
  map.size_x = cloud.width;
  map.size_y = cloud.height;
  map.dx_mm = x.slope;
  map.dy_mm = y.slope;
  map.x0_mm = x.offset;
  map.y0_mm = y.offset;
  map.source = cloud.source;
  map.z_mm.reserve(cloud.points.size());
  for (const Eigen::Vector3d& p : cloud.points) {
    map.z_mm.push_back(IsValid(p) ? p.z() : std::numeric_limits<double>::quiet_NaN());
  }
  return map;
}

PointCloudStats ComputeStats(const PointCloud& cloud) {
  PointCloudStats stats;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const Eigen::Vector3d& p : cloud.points) {
    if (!IsValid(p)) continue;
    ++stats.valid_points;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (stats.valid_points > 0) {
    stats.min = lo;
    stats.max = hi;
  }
  return stats;
}

}  // namespace fvm::imaging
