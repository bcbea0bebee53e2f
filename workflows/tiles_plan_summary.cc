// What `fvm tiles plan` tells its user (workflows/tiles_plan.h): the --json document and the printed text.

#include <fmt/core.h>

#include <cmath>

#include "workflows/tiles_plan.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

std::string Duration(double seconds) {
  const long s = std::lround(seconds);
  return fmt::format("{}:{:02d}:{:02d}", s / 3600, (s / 60) % 60, s % 60);
}

std::string Gigabytes(double bytes) { return fmt::format("{:.2f} GB", bytes / 1e9); }

Json CostJson(const imaging::ScanCost& cost) {
  return {{"tiles", cost.tiles}, {"seconds", cost.seconds}, {"bytes", cost.bytes}};
}

Json RegionJson(const TilesPlan& p) {
  Json out;
  out["lens"] = p.options.fov_mm > 0.0 ? Json(nullptr) : Json(p.options.lens);
  out["fov_mm"] = p.plan.fov_mm;
  out["overlap"] = p.plan.overlap;
  out["step_mm"] = p.grid.step_mm;
  out["region"] = {{"x0", p.region.x0}, {"y0", p.region.y0}, {"x1", p.region.x1}, {"y1", p.region.y1}};
  out["stitched"] = {{"rows", p.grid.rows}, {"cols", p.grid.cols}};
  out["stitched"].update(CostJson(p.stitched));
  if (p.free) {
    Json covers = Json::array();
    for (const auto& c : p.free->covers) covers.push_back({{"id", c.feature_id}, {"tiles", c.tiles.size()}});
    out["stitching_free"] = CostJson(*p.free_cost);
    out["stitching_free"]["features"] = covers;
  } else {
    out["stitching_free"] = nullptr;
  }
  return out;
}

std::string RegionText(const TilesPlan& p) {
  const imaging::TilePlanOptions& o = p.plan;
  const imaging::Region& r = p.region;
  std::string text = fmt::format("field {} mm, overlap {:.4g} % (step {:.4f} mm), region x {}..{} mm, y {}..{} mm\n",
                                 o.fov_mm, o.overlap * 100, p.grid.step_mm, r.x0, r.x1, r.y0, r.y1);
  text += fmt::format("first tile at lowest X, highest Y: centre ({:.4f}, {:.4f}) mm; columns -X to +X, each +Y to -Y\n\n",
                      p.grid.tiles[0].centre_mm.x(), p.grid.tiles[0].centre_mm.y());
  text += fmt::format("{:<16}{:>8}{:>12}{:>12}\n", "layout", "tiles", "scan time", "data");
  text += fmt::format("{:<16}{:>8}{:>12}{:>12}   ({} x {})\n", "stitched", p.stitched.tiles, Duration(p.stitched.seconds),
                      Gigabytes(p.stitched.bytes), p.grid.cols, p.grid.rows);
  if (p.free) {
    text += fmt::format("{:<16}{:>8}{:>12}{:>12}   ({} features)\n", "stitching-free", p.free_cost->tiles,
                        Duration(p.free_cost->seconds), Gigabytes(p.free_cost->bytes), p.free->covers.size());
  }
  text += fmt::format("\ncosts assume {} s and {} x {} px of {} bytes per tile (--seconds-per-tile, --tile-pixels, "
                      "--bytes-per-pixel)\n",
                      o.seconds_per_tile, o.pixels_x, o.pixels_y, o.bytes_per_pixel);
  return text;
}

Json ScansJson(const TilesPlan& p) {
  Json out;
  out["fov_mm"] = p.plan.fov_mm;
  out["overlap"] = p.plan.overlap;
  out["step_mm"] = p.plan.fov_mm * (1.0 - p.plan.overlap);
  out["paths"] = Json::array();
  for (size_t k = 0; k < p.paths.size(); ++k) {
    const imaging::ScanPath& path = p.paths[k];
    const imaging::ScanCost& cost = p.path_costs[k];
    const std::string layout = ScanLayoutPath(p.options, path.name);
    out["paths"].push_back({{"name", path.name},
                            {"tiles", cost.tiles},
                            {"from_mm", {path.tiles.front().centre_mm.x(), path.tiles.front().centre_mm.y(), path.z_mm}},
                            {"to_mm", {path.tiles.back().centre_mm.x(), path.tiles.back().centre_mm.y(), path.z_mm}},
                            {"seconds", cost.seconds},
                            {"bytes", cost.bytes},
                            {"layout", layout.empty() ? Json(nullptr) : Json(layout)}});
  }
  out["total"] = CostJson(p.total);
  return out;
}

std::string ScansText(const TilesPlan& p) {
  const imaging::TilePlanOptions& o = p.plan;
  std::string text = fmt::format("calibration scans: field {} mm, overlap {:.4g} % (step {:.4f} mm per axis), paths of "
                                 "{} mm\n",
                                 o.fov_mm, o.overlap * 100, o.fov_mm * (1.0 - o.overlap), p.options.length_mm);
  text += fmt::format("  {:<12} {:>6} {:>24} {:>24} {:>9} {:>9}\n", "path", "tiles", "first tile (mm)", "last tile (mm)",
                      "time h", "GB");
  const auto point = [](const Eigen::Vector2d& xy, double z) {
    return fmt::format("{:.2f}, {:.2f}, {:.1f}", xy.x(), xy.y(), z);
  };
  for (size_t k = 0; k < p.paths.size(); ++k) {
    const imaging::ScanPath& path = p.paths[k];
    text += fmt::format("  {:<12} {:>6} {:>24} {:>24} {:>9.2f} {:>9.2f}\n", path.name, p.path_costs[k].tiles,
                        point(path.tiles.front().centre_mm, path.z_mm), point(path.tiles.back().centre_mm, path.z_mm),
                        p.path_costs[k].seconds / 3600.0, p.path_costs[k].bytes / 1e9);
  }
  text += fmt::format("  {:<12} {:>6} {:>24} {:>24} {:>9.2f} {:>9.2f}\n", "total", p.total.tiles, "", "",
                      p.total.seconds / 3600.0, p.total.bytes / 1e9);
  text += "Measure each path stitched and export its tiles with the encoder reading of each tile's centre; then\n"
          "  fvm calibrate --scan row.csv --scan column.csv --scan diagonal.csv --pixel-mm P --model 27 -o stage.json\n"
          "A second height (--heights -50,-40: a part with two levels, or on a spacer) lets the scans tell pitch and "
          "roll.\n";
  if (p.options.scan_dir.empty()) text += "(give --scan-dir DIR to write the layouts)\n";
  return text;
}

}  // namespace

Summary Summarize(const TilesPlan& plan) {
  if (plan.options.calibration_scan) return {ScansJson(plan), ScansText(plan), std::nullopt};
  return {RegionJson(plan), RegionText(plan), std::nullopt};
}

}  // namespace fvm::workflows
