#include "imaging/grid_resampling.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::imaging {
namespace {

// (s, t) in [0, 1]^2 such that the bilinear map of the corners p00, p10, p01, p11 reaches `target` (x, y), by
// Newton from the cell's centre; false when it does not converge or lands outside the cell.
bool InverseBilinear(const Eigen::Vector2d& p00, const Eigen::Vector2d& p10, const Eigen::Vector2d& p01,
                     const Eigen::Vector2d& p11, const Eigen::Vector2d& target, double* s, double* t) {
  double u = 0.5, v = 0.5;
  for (int iteration = 0; iteration < 10; ++iteration) {
    const Eigen::Vector2d at = (1 - u) * (1 - v) * p00 + u * (1 - v) * p10 + (1 - u) * v * p01 + u * v * p11;
    const Eigen::Vector2d r = at - target;
    Eigen::Matrix2d j;
    j.col(0) = (1 - v) * (p10 - p00) + v * (p11 - p01);
    j.col(1) = (1 - u) * (p01 - p00) + u * (p11 - p10);
    const double det = j.determinant();
    if (!(std::abs(det) > 0.0)) return false;
    const Eigen::Vector2d step = j.inverse() * r;
    u -= step.x();
    v -= step.y();
    if (step.cwiseAbs().maxCoeff() < 1e-12) break;
  }
  constexpr double kEdge = 1e-9;  // a node on a shared edge belongs to both cells; either gives the same height
  if (u < -kEdge || u > 1 + kEdge || v < -kEdge || v > 1 + kEdge) return false;
  *s = std::clamp(u, 0.0, 1.0);
  *t = std::clamp(v, 0.0, 1.0);
  return true;
}

}  // namespace

HeightMap ResampleOnGrid(const PointCloud& cloud, double pixel_mm, const std::string& name) {
  if (!(pixel_mm > 0.0) || !std::isfinite(pixel_mm)) {
    throw InputError(name + ": the resampling pixel must be a positive size in mm, e.g. 0.01");
  }
  if (!cloud.IsOrganised() ||
      cloud.points.size() != static_cast<std::size_t>(cloud.width) * static_cast<std::size_t>(cloud.height)) {
    throw InputError(name + ": only a height map or an organised cloud can be resampled on a grid; an unorganised "
                            "cloud has no cells to interpolate in");
  }
  const auto point = [&](int ix, int iy) -> const Eigen::Vector3d& {
    return cloud.points[static_cast<std::size_t>(iy) * static_cast<std::size_t>(cloud.width) + static_cast<std::size_t>(ix)];
  };
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Eigen::Vector3d& p : cloud.points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  if (!lo.allFinite()) throw InputError(name + ": no valid point to resample");
  const double x0 = std::ceil(lo.x() / pixel_mm - 1e-9), y0 = std::ceil(lo.y() / pixel_mm - 1e-9);
  const double nx = std::floor(hi.x() / pixel_mm + 1e-9) - x0 + 1, ny = std::floor(hi.y() / pixel_mm + 1e-9) - y0 + 1;
  if (!(nx >= 1 && ny >= 1) || nx * ny > static_cast<double>(std::numeric_limits<std::int32_t>::max())) {
    throw InputError(name + ": a grid of " + FormatShortest(pixel_mm) + " mm pixels over the scan would hold " +
                     FormatShortest(std::max(nx, 0.0) * std::max(ny, 0.0)) + " nodes; choose a pixel near the scan's own");
  }
  HeightMap map;
  map.size_x = static_cast<int>(nx);
  map.size_y = static_cast<int>(ny);
  map.dx_mm = map.dy_mm = pixel_mm;
  map.x0_mm = x0 * pixel_mm;
  map.y0_mm = y0 * pixel_mm;
  map.source = cloud.source;
  map.z_mm.assign(static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y),
                  std::numeric_limits<double>::quiet_NaN());
  for (int iy = 0; iy + 1 < cloud.height; ++iy) {
    for (int ix = 0; ix + 1 < cloud.width; ++ix) {
      const Eigen::Vector3d &a = point(ix, iy), &b = point(ix + 1, iy), &c = point(ix, iy + 1), &d = point(ix + 1, iy + 1);
      if (!a.allFinite() || !b.allFinite() || !c.allFinite() || !d.allFinite()) continue;
      const double cell_lo_x = std::min({a.x(), b.x(), c.x(), d.x()}), cell_hi_x = std::max({a.x(), b.x(), c.x(), d.x()});
      const double cell_lo_y = std::min({a.y(), b.y(), c.y(), d.y()}), cell_hi_y = std::max({a.y(), b.y(), c.y(), d.y()});
      const int jx0 = std::max(0, static_cast<int>(std::ceil((cell_lo_x - map.x0_mm) / pixel_mm - 1e-9)));
      const int jx1 = std::min(map.size_x - 1, static_cast<int>(std::floor((cell_hi_x - map.x0_mm) / pixel_mm + 1e-9)));
      const int jy0 = std::max(0, static_cast<int>(std::ceil((cell_lo_y - map.y0_mm) / pixel_mm - 1e-9)));
      const int jy1 = std::min(map.size_y - 1, static_cast<int>(std::floor((cell_hi_y - map.y0_mm) / pixel_mm + 1e-9)));
      for (int jy = jy0; jy <= jy1; ++jy) {
        for (int jx = jx0; jx <= jx1; ++jx) {
          if (std::isfinite(map.at(jx, jy))) continue;  // filled by a neighbouring cell sharing the edge
          const Eigen::Vector2d node(map.x0_mm + jx * pixel_mm, map.y0_mm + jy * pixel_mm);
          double s = 0, t = 0;
          if (!InverseBilinear(a.head<2>(), b.head<2>(), c.head<2>(), d.head<2>(), node, &s, &t)) continue;
          map.at(jx, jy) = (1 - s) * (1 - t) * a.z() + s * (1 - t) * b.z() + (1 - s) * t * c.z() + s * t * d.z();
        }
      }
    }
  }
  return map;
}

}  // namespace fvm::imaging
