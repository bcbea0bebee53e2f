#pragma once
// `fvm tiles plan`: the stitched tile grid of a region and the stitching-free tiles that cover given features, with
// their scan time and data volume (imaging/tile_plan.h); or, with calibration_scan, the row, column and diagonal
// paths over the travel that `fvm calibrate --scan` calibrates from. The layouts it writes, and its summary (the
// --json document and the printed text), for every front end.

#include <optional>
#include <string>
#include <vector>

#include "imaging/tile_plan.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct TilesPlanOptions {
  std::string lens = "10x";  // --lens: the field from the lens table
  double fov_mm = 0.0;       // --fov-mm: > 0 instead of the lens's field
  std::optional<imaging::Region> region;  // --region; none: the features' bounding box
  double overlap = 0.2;      // --overlap, a fraction
  std::string features;      // --features: a centre export whose calottes a stitching-free scan covers
  std::string artefact;      // --artefact: grid6x6 or bar17, in its own frame
  double radius_mm = 0.0;    // --radius-mm: > 0 overrides the file's or artefact's
  double seconds_per_tile = imaging::TilePlanOptions{}.seconds_per_tile;
  int tile_width_px = imaging::TilePlanOptions{}.pixels_x, tile_height_px = imaging::TilePlanOptions{}.pixels_y;
  int bytes_per_pixel = imaging::TilePlanOptions{}.bytes_per_pixel;
  bool calibration_scan = false;  // --calibration-scan: paths for fvm calibrate --scan instead of a region's grid
  double travel_width_mm = 200.0, travel_height_mm = 200.0;  // --travel WxH: stage coordinates -W..0, -H..0
  double length_mm = imaging::CalibrationScanOptions{}.length_mm;
  std::vector<double> heights_mm{-50.0};  // --heights: the encoder z of each set of paths
  std::string scan_dir;                   // --scan-dir: where each path's layout is written; empty: none
  // The cost model and field (FindLens: InputError naming the known lenses). Throws InputError for bad costs.
  imaging::TilePlanOptions PlanOptions() const;
};

struct TilesPlan {
  TilesPlanOptions options;
  imaging::TilePlanOptions plan;
  // A region's grid (not calibration_scan):
  imaging::Region region;
  imaging::TileGrid grid;
  imaging::ScanCost stitched;
  std::optional<imaging::StitchingFreePlan> free;  // with features
  std::optional<imaging::ScanCost> free_cost;
  // Calibration scans: each path, its cost, the sum.
  std::vector<imaging::ScanPath> paths;
  std::vector<imaging::ScanCost> path_costs;
  imaging::ScanCost total;
};

// Throws InputError naming the option (an unknown lens or artefact, --features with --artefact, a feature without
// a radius, no region, a feature outside the grid, a path longer than the travel).
TilesPlan PlanTiles(const TilesPlanOptions& options);

// The layouts (file,row,col,x,y; a '#' line saying how they were planned) of the stitched grid and of the
// stitching-free tiles (this needs features).
std::string StitchedLayoutText(const TilesPlan& plan);
std::string StitchingFreeLayoutText(const TilesPlan& plan);
// Where the calibration scan `name` writes its layout with scan_dir; empty without.
std::string ScanLayoutPath(const TilesPlanOptions& options, const std::string& name);
// Each calibration scan's layout (file,row,col,x,y,z) into scan_dir, when given.
void WriteScanLayouts(const TilesPlan& plan);

Summary Summarize(const TilesPlan& plan);

}  // namespace fvm::workflows
