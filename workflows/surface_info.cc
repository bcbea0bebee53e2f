#include "workflows/surface_info.h"

#include <fmt/core.h>

#include "core/input_error.h"
#include "imaging/height_map.h"
#include "imaging/point_cloud.h"

namespace fvm::workflows {
namespace {

SurfaceInfo DescribeMap(const imaging::HeightMap& map) {
  SurfaceInfo s;
  s.kind = "height_map";
  s.source = map.source;
  s.size_x = map.size_x;
  s.size_y = map.size_y;
  s.dx_mm = map.dx_mm;
  s.dy_mm = map.dy_mm;
  s.x0_mm = map.x0_mm;
  s.y0_mm = map.y0_mm;
  s.points = map.z_mm.size();
  s.organised = true;
  s.intensity = !map.intensity.empty() && map.intensity.size() == map.z_mm.size();
  s.notes = map.notes;
  const imaging::HeightMapStats stats = imaging::ComputeStats(map);
  s.valid_points = stats.valid_points;
  if (stats.valid_points > 0) {
    s.z_min = stats.z_min_mm;
    s.z_max = stats.z_max_mm;
    s.sq_mm = stats.sq_mm;
    s.x_min = map.x0_mm;
    s.x_max = map.x0_mm + (map.size_x - 1) * map.dx_mm;
    s.y_min = map.y0_mm;
    s.y_max = map.y0_mm + (map.size_y - 1) * map.dy_mm;
  }
  return s;
}

SurfaceInfo DescribeCloud(const imaging::PointCloud& cloud, const std::string& name) {
  SurfaceInfo s;
  s.kind = "point_cloud";
  s.source = cloud.source;
  s.size_x = cloud.width;
  s.size_y = cloud.height;
  s.points = cloud.points.size();
  s.organised = cloud.IsOrganised();
  if (cloud.IsOrganised()) {
    try {  // an organised cloud on a regular grid is a height map in disguise: report its grid
      const imaging::HeightMap map = imaging::CloudToHeightMap(cloud, name);
      s.dx_mm = map.dx_mm;
      s.dy_mm = map.dy_mm;
      s.x0_mm = map.x0_mm;
      s.y0_mm = map.y0_mm;
    } catch (const InputError&) {
    }
  }
  const imaging::PointCloudStats stats = imaging::ComputeStats(cloud);
  s.valid_points = stats.valid_points;
  if (stats.valid_points > 0) {
    s.x_min = stats.min.x(), s.x_max = stats.max.x();
    s.y_min = stats.min.y(), s.y_max = stats.max.y();
    s.z_min = stats.min.z(), s.z_max = stats.max.z();
  }
  return s;
}

nlohmann::ordered_json OrNull(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

std::string InUm(double mm) { return fmt::format("{:.6g} um", mm * 1000.0); }

std::string InfoText(const std::string& name, const SurfaceInfo& s) {
  const bool cloud = s.kind == "point_cloud";
  std::string t = fmt::format("{}\n", name);
  t += fmt::format("  format        {}, {}\n", cloud ? "point cloud" : "height map", s.source.empty() ? s.format : s.source);
  if (cloud) {
    t += fmt::format("  points        {}{}\n", s.points,
                     s.organised ? fmt::format(", organised {} x {}", s.size_x, s.size_y) : ", unorganised");
  }
  if (s.dx_mm) {
    t += fmt::format("  grid          {} x {} points, {} x {} pixels, origin ({:.6f}, {:.6f}) mm\n", s.size_x,
                     s.size_y, InUm(*s.dx_mm), InUm(*s.dy_mm), *s.x0_mm, *s.y0_mm);
  }
  if (s.intensity) t += "  intensity     an intensity image on the same grid\n";
  for (const std::string& note : s.notes) t += fmt::format("  note          {}\n", note);
  const double percent = s.points > 0 ? 100.0 * static_cast<double>(s.valid_points) / static_cast<double>(s.points) : 0;
  t += fmt::format("  valid points  {} of {} ({:.2f} %)\n", s.valid_points, s.points, percent);
  if (s.valid_points == 0) return t + "  no valid point: the file holds no measurement\n";
  t += fmt::format("  x range       {:.6f} .. {:.6f} mm\n", *s.x_min, *s.x_max);
  t += fmt::format("  y range       {:.6f} .. {:.6f} mm\n", *s.y_min, *s.y_max);
  t += fmt::format("  z range       {:.6f} .. {:.6f} mm ({})\n", *s.z_min, *s.z_max, InUm(*s.z_max - *s.z_min));
  if (s.sq_mm) t += fmt::format("  Sq            {} (RMS height about the mean, no form removed)\n", InUm(*s.sq_mm));
  return t;
}

}  // namespace

SurfaceInfo DescribeSurface(const imaging::Surface& surface, const std::string& name) {
  SurfaceInfo s = surface.height_map ? DescribeMap(*surface.height_map) : DescribeCloud(*surface.cloud, name);
  s.format = imaging::FormatName(surface.format);
  return s;
}

Summary Summarize(const SurfaceInfo& s, const std::string& name) {
  Summary summary;
  nlohmann::ordered_json& out = summary.json;  // the contract's keys first, in its order
  out["size_x"] = s.size_x;
  out["size_y"] = s.size_y;
  out["dx_mm"] = OrNull(s.dx_mm);
  out["dy_mm"] = OrNull(s.dy_mm);
  out["valid_points"] = s.valid_points;
  out["z_min_mm"] = OrNull(s.z_min);
  out["z_max_mm"] = OrNull(s.z_max);
  out["format"] = s.format;
  out["kind"] = s.kind;
  out["source"] = s.source;
  out["points"] = s.points;
  out["organised"] = s.organised;
  out["x0_mm"] = OrNull(s.x0_mm);
  out["y0_mm"] = OrNull(s.y0_mm);
  out["x_min_mm"] = OrNull(s.x_min);
  out["x_max_mm"] = OrNull(s.x_max);
  out["y_min_mm"] = OrNull(s.y_min);
  out["y_max_mm"] = OrNull(s.y_max);
  out["sq_um"] = s.sq_mm ? nlohmann::ordered_json(*s.sq_mm * 1e3) : nlohmann::ordered_json(nullptr);
  out["intensity"] = s.intensity;
  out["notes"] = s.notes;
  summary.text = InfoText(name, s);
  return summary;
}

}  // namespace fvm::workflows
