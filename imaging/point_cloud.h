#pragma once
// A point cloud in mm, organised (points on a width x height grid, row-major, as an instrument's camera sees
// them) or unorganised (height 1, as PCL has it), and its conversions to and from a height map.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "imaging/height_map.h"

namespace fvm::imaging {

struct PointCloud {
  std::vector<Eigen::Vector3d> points;  // mm; NaN coordinates mark a missing point (organised clouds keep them)
  int width = 0;                        // points.size() == width * height
  int height = 0;                       // 1 for an unorganised cloud
  std::string source{};                 // what the reader found about the origin; may be empty

  bool IsOrganised() const { return height > 1; }
};

// An unorganised cloud of the given points (width = points, height = 1).
PointCloud MakeUnorganisedCloud(std::vector<Eigen::Vector3d> points);

// Every grid point becomes a point, invalid ones NaN: the organised cloud of the map.
PointCloud HeightMapToCloud(const HeightMap& map);

// The grid an organised cloud lies on: x must depend on the column only and y on the row only, both
// increasing, to within 1 % of the spacing. Throws InputError naming `name` otherwise (an unorganised or
// perspective cloud, too few valid points to tell the spacing).
HeightMap CloudToHeightMap(const PointCloud& cloud, const std::string& name);

struct PointCloudStats {
  std::size_t valid_points = 0;                   // with three finite coordinates
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  // over valid points; zero when there are none
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};

PointCloudStats ComputeStats(const PointCloud& cloud);

}  // namespace fvm::imaging
