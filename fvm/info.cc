// fvm info FILE: what a surface or point-cloud file holds (format, grid, valid points, height range), so that a
// user can check an export before fitting calottes in it.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "fvm/commands.h"
#include "fvm/surface_read_args.h"
#include "imaging/height_map.h"
#include "core/number_text.h"
#include "imaging/point_cloud.h"
#include "imaging/io/surface_file.h"

namespace fvm::cli {
namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
  SurfaceReadArgs read;
};

// What one file holds, in the terms of the JSON contract.
struct Summary {
  std::string kind;  // "height_map" or "point_cloud"
  std::string source;
  int size_x = 0, size_y = 0;
  std::optional<double> dx_mm, dy_mm, x0_mm, y0_mm;  // the grid, when there is one
  std::size_t points = 0, valid_points = 0;
  std::optional<double> x_min, x_max, y_min, y_max, z_min, z_max;  // over valid points
  std::optional<double> sq_mm;  // height maps: RMS height about the mean
  bool organised = false;
  bool intensity = false;          // the file holds an intensity image on the heights' grid
  std::vector<std::string> notes;  // what the reader found unusual and read anyway
};

Summary SummariseMap(const imaging::HeightMap& map) {
  Summary s;
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

Summary SummariseCloud(const imaging::PointCloud& cloud, const std::string& file) {
  Summary s;
  s.kind = "point_cloud";
  s.source = cloud.source;
  s.size_x = cloud.width;
  s.size_y = cloud.height;
  s.points = cloud.points.size();
  s.organised = cloud.IsOrganised();
  if (cloud.IsOrganised()) {
    try {  // an organised cloud on a regular grid is a height map in disguise: report its grid
      const imaging::HeightMap map = imaging::CloudToHeightMap(cloud, file);
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

nlohmann::ordered_json Optional(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

std::string Um(double mm) { return fmt::format("{:.6g} um", mm * 1000.0); }

void PrintText(const std::string& file, const std::string& format, const Summary& s) {
  const bool cloud = s.kind == "point_cloud";
  fmt::print("{}\n", file);
  fmt::print("  format        {}, {}\n", cloud ? "point cloud" : "height map", s.source.empty() ? format : s.source);
  if (cloud) {
    fmt::print("  points        {}{}\n", s.points,
               s.organised ? fmt::format(", organised {} x {}", s.size_x, s.size_y) : ", unorganised");
  }
  if (s.dx_mm) {
    fmt::print("  grid          {} x {} points, {} x {} pixels, origin ({:.6f}, {:.6f}) mm\n", s.size_x, s.size_y,
               Um(*s.dx_mm), Um(*s.dy_mm), *s.x0_mm, *s.y0_mm);
  }
  if (s.intensity) fmt::print("  intensity     an intensity image on the same grid\n");
  for (const std::string& note : s.notes) fmt::print("  note          {}\n", note);
  const double percent = s.points > 0 ? 100.0 * static_cast<double>(s.valid_points) / static_cast<double>(s.points) : 0;
  fmt::print("  valid points  {} of {} ({:.2f} %)\n", s.valid_points, s.points, percent);
  if (s.valid_points == 0) {
    fmt::print("  no valid point: the file holds no measurement\n");
    return;
  }
  fmt::print("  x range       {:.6f} .. {:.6f} mm\n", *s.x_min, *s.x_max);
  fmt::print("  y range       {:.6f} .. {:.6f} mm\n", *s.y_min, *s.y_max);
  fmt::print("  z range       {:.6f} .. {:.6f} mm ({})\n", *s.z_min, *s.z_max, Um(*s.z_max - *s.z_min));
  if (s.sq_mm) fmt::print("  Sq            {} (RMS height about the mean, no form removed)\n", Um(*s.sq_mm));
}

void RunInfo(const InfoArgs& args) {
  const imaging::Surface surface = imaging::ReadSurface(args.file, args.read.ToOptions());
  const std::string format = imaging::FormatName(surface.format);
  const Summary s = surface.height_map ? SummariseMap(*surface.height_map) : SummariseCloud(*surface.cloud, args.file);

  if (!args.json) {
    PrintText(args.file, format, s);
    return;
  }
  nlohmann::ordered_json out;  // the contract's keys first, in its order
  out["size_x"] = s.size_x;
  out["size_y"] = s.size_y;
  out["dx_mm"] = Optional(s.dx_mm);
  out["dy_mm"] = Optional(s.dy_mm);
  out["valid_points"] = s.valid_points;
  out["z_min_mm"] = Optional(s.z_min);
  out["z_max_mm"] = Optional(s.z_max);
  out["file"] = args.file;
  out["format"] = format;
  out["kind"] = s.kind;
  out["source"] = s.source;
  out["points"] = s.points;
  out["organised"] = s.organised;
  out["x0_mm"] = Optional(s.x0_mm);
  out["y0_mm"] = Optional(s.y0_mm);
  out["x_min_mm"] = Optional(s.x_min);
  out["x_max_mm"] = Optional(s.x_max);
  out["y_min_mm"] = Optional(s.y_min);
  out["y_max_mm"] = Optional(s.y_max);
  out["sq_um"] = s.sq_mm ? nlohmann::ordered_json(*s.sq_mm * 1e3) : nlohmann::ordered_json(nullptr);
  out["intensity"] = s.intensity;
  out["notes"] = s.notes;
  fmt::print("{}\n", out.dump(2));
}

}  // namespace

void RegisterInfo(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* sub = app.add_subcommand("info", "what a surface or point-cloud file holds");
  AddDetails(sub,
      "Reads a measurement file and tells what it holds: its format, grid (points, pixel size, origin), how many "
      "points are valid and the range of heights. Reads X3P (ISO 25178-72), Alicona AL3D, ISO 25178-71 SDF, the "
      "exports of other instruments (Sensofar PLU and PLUx, Zygo MetroPro DAT, Wyko OPD, Digital Surf SUR, NMS, "
      "GelSight TMD), height-map images (TIFF, EXR, PNG through OpenImageIO), PCD and PLY point clouds, and XYZ/CSV "
      "text (x y z in mm per line). Checksums in X3P files are verified. What was unusual about a file and read anyway "
      "(an X3P zipped around its folder, archive clutter, empty optional elements) is listed as notes.");
  sub->add_option("FILE", args->file, "the surface or point-cloud file")->required();
  sub->add_flag("--json", args->json,
                "print one JSON document {\"size_x\", \"size_y\", \"dx_mm\", \"dy_mm\", \"valid_points\", "
                "\"z_min_mm\", \"z_max_mm\", ..., \"intensity\", \"notes\"}; values the file does not have are null");
  args->read.AddOptions(*sub);
  sub->footer("Example: fvm info scan.x3p --json");
  sub->callback([args] { RunInfo(*args); });
}

}  // namespace fvm::cli
