#include "workflows/tiles_plan.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "artefacts/geometry/artefact.h"
#include "artefacts/io/centre_export.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/tile_layout.h"
#include "workflows/tile_set_files.h"

namespace fvm::workflows {
namespace {

using imaging::Feature;

std::vector<Feature> LoadFeatures(const TilesPlanOptions& options) {
  std::vector<Feature> features;
  if (!options.artefact.empty()) {
    const artefacts::Artefact artefact = artefacts::KnownArtefact(options.artefact);
    for (const auto& c : artefact.calottes) {
      features.push_back({c.id, c.centre.head<2>(), options.radius_mm > 0.0 ? options.radius_mm : c.radius_mm});
    }
  }
  if (!options.features.empty()) {
    const artefacts::CentreExport centres = artefacts::ReadCentreExport(options.features);
    for (const auto& c : centres.centres) {
      const double r = options.radius_mm > 0.0 ? options.radius_mm : c.radius_mm.value_or(0.0);
      if (!(r > 0.0)) {
        throw InputError(fmt::format("{}:{}: calotte {} has no radius; add a radius column or give --radius-mm MM",
                                     options.features, c.line, c.id));
      }
      features.push_back({c.id, c.position.head<2>(), r});
    }
  }
  return features;
}

// The features' bounding box: the smallest region that holds every feature whole.
imaging::Region BoundingRegion(const std::vector<Feature>& features) {
  imaging::Region region{1e300, 1e300, -1e300, -1e300};
  for (const auto& f : features) {
    region.x0 = std::min(region.x0, f.centre_mm.x() - f.radius_mm);
    region.y0 = std::min(region.y0, f.centre_mm.y() - f.radius_mm);
    region.x1 = std::max(region.x1, f.centre_mm.x() + f.radius_mm);
    region.y1 = std::max(region.y1, f.centre_mm.y() + f.radius_mm);
  }
  return region;
}

void PlanCalibrationScans(TilesPlan& plan) {
  const TilesPlanOptions& o = plan.options;
  imaging::CalibrationScanOptions scan;
  scan.travel_min_mm = {-o.travel_width_mm, -o.travel_height_mm};
  scan.travel_max_mm = {0.0, 0.0};
  scan.length_mm = o.length_mm;
  scan.heights_mm = o.heights_mm;
  plan.paths = imaging::PlanCalibrationScans(scan, plan.plan);
  for (const imaging::ScanPath& path : plan.paths) {
    const imaging::ScanCost cost = imaging::EstimateScan(static_cast<int>(path.tiles.size()), plan.plan);
    plan.path_costs.push_back(cost);
    plan.total.tiles += cost.tiles;
    plan.total.seconds += cost.seconds;
    plan.total.bytes += cost.bytes;
  }
}

void PlanRegion(TilesPlan& plan) {
  const TilesPlanOptions& o = plan.options;
  if (!o.features.empty() && !o.artefact.empty()) throw InputError("give --features or --artefact, not both");
  const std::vector<Feature> features = LoadFeatures(o);
  if (o.region) {
    plan.region = *o.region;
  } else if (!features.empty()) {
    plan.region = BoundingRegion(features);
  } else {
    throw InputError("give --region x0,y0,x1,y1 (mm), or --features / --artefact to cover their bounding box");
  }
  plan.grid = imaging::PlanStitchedGrid(plan.region, plan.plan);
  plan.stitched = imaging::EstimateScan(static_cast<int>(plan.grid.tiles.size()), plan.plan);
  if (!features.empty()) {
    plan.free = imaging::PlanStitchingFree(plan.grid, features);
    plan.free_cost = imaging::EstimateScan(static_cast<int>(plan.free->tiles.size()), plan.plan);
  }
}

std::string Describe(const TilesPlan& plan) {
  const imaging::Region& r = plan.region;
  return fmt::format("fvm tiles plan: field {} mm, overlap {:.4g} %, step {:.6f} mm; region {},{},{},{} mm; scan order "
                     "column by column from -X to +X, each from +Y to -Y; x,y = tile centre (mm)",
                     plan.plan.fov_mm, plan.plan.overlap * 100, plan.grid.step_mm, r.x0, r.y0, r.x1, r.y1);
}

}  // namespace

imaging::TilePlanOptions TilesPlanOptions::PlanOptions() const {
  imaging::TilePlanOptions plan;
  plan.fov_mm = fov_mm > 0.0 ? fov_mm : imaging::FindLens(lens).fov_mm;
  plan.overlap = overlap;
  plan.seconds_per_tile = seconds_per_tile;
  plan.bytes_per_pixel = bytes_per_pixel;
  plan.pixels_x = tile_width_px;
  plan.pixels_y = tile_height_px;
  plan.Check();
  return plan;
}

TilesPlan PlanTiles(const TilesPlanOptions& options) {
  TilesPlan plan;
  plan.options = options;
  plan.plan = options.PlanOptions();
  if (options.calibration_scan) {
    PlanCalibrationScans(plan);
  } else {
    PlanRegion(plan);
  }
  return plan;
}

std::string StitchedLayoutText(const TilesPlan& plan) { return LayoutText(plan.grid.tiles, Describe(plan) + "; stitched"); }

std::string StitchingFreeLayoutText(const TilesPlan& plan) {
  if (!plan.free) throw InputError("--free-layout needs --features or --artefact");
  return LayoutText(plan.free->tiles, Describe(plan) + "; stitching-free");
}

std::string ScanLayoutPath(const TilesPlanOptions& options, const std::string& name) {
  if (options.scan_dir.empty()) return {};
  return (std::filesystem::path(options.scan_dir) / (name + ".csv")).string();
}

void WriteScanLayouts(const TilesPlan& plan) {
  if (plan.options.scan_dir.empty()) return;
  for (const imaging::ScanPath& path : plan.paths) {
    std::vector<imaging::TileLayoutEntry> entries;
    for (const imaging::Tile& t : path.tiles) {
      imaging::TileLayoutEntry e;
      e.file = fmt::format("{}/tile_{:03d}.tif", path.name, t.index);
      e.row = t.row;
      e.col = t.col;
      e.stage_mm = t.centre_mm;
      e.stage_z_mm = path.z_mm;
      entries.push_back(e);
    }
    std::filesystem::create_directories(plan.options.scan_dir);
    WriteFileAtomically(ScanLayoutPath(plan.options, path.name), imaging::FormatTileLayout(entries));
  }
}

}  // namespace fvm::workflows
