// fvm tiles plan: tile layouts with and without stitching (imaging/tile_plan.h); `synthesize` and `simulate` in
// fvm/tiles_synthesize.cc and fvm/tiles_simulate.cc.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <memory>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "core/file_io.h"
#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/height_tile_synthesis.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "artefacts/simulation/rendered_stitching_strategy.h"
#include "artefacts/simulation/stitching_strategy.h"
#include "artefacts/simulation/sparse_tile_synthesis.h"
#include "artefacts/simulation/tile_synthesis.h"
#include "stage/io/calibration_file.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "fvm/tile_set_files.h"
#include "imaging/io/tile_image.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_plan.h"
#include "imaging/tile_registration.h"

namespace fvm::cli {
namespace {

using imaging::Feature;

struct PlanArgs {
  std::string lens = "10x";
  double fov_mm = 0.0;
  std::string region;
  std::string overlap = "0.2";
  std::string features;
  std::string artefact;
  double radius_mm = 0.0;
  double seconds_per_tile = imaging::TilePlanOptions{}.seconds_per_tile;
  std::string tile_pixels = "1024x1024";
  int bytes_per_pixel = imaging::TilePlanOptions{}.bytes_per_pixel;
  std::string output;
  std::string free_output;
  bool json = false;
  bool calibration_scan = false;  // paths for fvm calibrate --scan instead of a region's grid
  std::string travel = "200x200";
  double length_mm = imaging::CalibrationScanOptions{}.length_mm;
  std::string heights = "-50";
  std::string scan_dir;
};

std::vector<Feature> LoadFeatures(const PlanArgs& args) {
  std::vector<Feature> features;
  if (!args.artefact.empty()) {
    const artefacts::Artefact artefact = artefacts::KnownArtefact(args.artefact);
    for (const auto& c : artefact.calottes) {
      features.push_back({c.id, c.centre.head<2>(), args.radius_mm > 0.0 ? args.radius_mm : c.radius_mm});
    }
  }
  if (!args.features.empty()) {
    const artefacts::CentreExport centres = artefacts::ReadCentreExport(args.features);
    for (const auto& c : centres.centres) {
      const double r = args.radius_mm > 0.0 ? args.radius_mm : c.radius_mm.value_or(0.0);
      if (!(r > 0.0)) {
        throw InputError(fmt::format("{}:{}: calotte {} has no radius; add a radius column or give --radius-mm MM",
                                     args.features, c.line, c.id));
      }
      features.push_back({c.id, c.position.head<2>(), r});
    }
  }
  return features;
}

std::string Duration(double seconds) {
  const long s = std::lround(seconds);
  return fmt::format("{}:{:02d}:{:02d}", s / 3600, (s / 60) % 60, s % 60);
}

std::string Bytes(double bytes) { return fmt::format("{:.2f} GB", bytes / 1e9); }

// --calibration-scan: a row, a column and a diagonal over the travel (and again at further heights), each written as
// a layout for fvm calibrate --scan, with their tiles, time and data.
void RunCalibrationScanPlan(const PlanArgs& args, const imaging::TilePlanOptions& options) {
  imaging::CalibrationScanOptions scan;
  const std::string travel = args.travel.find('x') == std::string::npos ? "" : args.travel.substr(0, args.travel.find('x')) + "," + args.travel.substr(args.travel.find('x') + 1);
  const auto wh = ParseNumbers(travel, 2, "--travel " + args.travel, "200x200 (mm; stage coordinates -W..0, -H..0)");
  scan.travel_min_mm = {-wh[0], -wh[1]};
  scan.travel_max_mm = {0.0, 0.0};
  scan.length_mm = args.length_mm;
  scan.heights_mm = ParseNumberList(args.heights, "--heights", "-50,-40");
  const std::vector<imaging::ScanPath> paths = imaging::PlanCalibrationScans(scan, options);
  nlohmann::ordered_json out;
  out["fov_mm"] = options.fov_mm;
  out["overlap"] = options.overlap;
  out["step_mm"] = options.fov_mm * (1.0 - options.overlap);
  out["paths"] = nlohmann::ordered_json::array();
  imaging::ScanCost total;
  for (const imaging::ScanPath& path : paths) {
    const imaging::ScanCost cost = imaging::EstimateScan(static_cast<int>(path.tiles.size()), options);
    total.tiles += cost.tiles;
    total.seconds += cost.seconds;
    total.bytes += cost.bytes;
    std::string layout;
    if (!args.scan_dir.empty()) {
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
      layout = (std::filesystem::path(args.scan_dir) / (path.name + ".csv")).string();
      std::filesystem::create_directories(args.scan_dir);
      WriteFileAtomically(layout, imaging::FormatTileLayout(entries));
    }
    out["paths"].push_back({{"name", path.name},
                            {"tiles", cost.tiles},
                            {"from_mm", {path.tiles.front().centre_mm.x(), path.tiles.front().centre_mm.y(), path.z_mm}},
                            {"to_mm", {path.tiles.back().centre_mm.x(), path.tiles.back().centre_mm.y(), path.z_mm}},
                            {"seconds", cost.seconds},
                            {"bytes", cost.bytes},
                            {"layout", layout.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(layout)}});
  }
  out["total"] = {{"tiles", total.tiles}, {"seconds", total.seconds}, {"bytes", total.bytes}};
  if (args.json) {
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("calibration scans: field {} mm, overlap {:.4g} % (step {:.4f} mm per axis), paths of {} mm\n", options.fov_mm,
             options.overlap * 100, options.fov_mm * (1.0 - options.overlap), args.length_mm);
  fmt::print("  {:<12} {:>6} {:>24} {:>24} {:>9} {:>9}\n", "path", "tiles", "first tile (mm)", "last tile (mm)", "time h", "GB");
  for (const auto& p : out["paths"]) {
    const auto point = [](const nlohmann::ordered_json& v) {
      return fmt::format("{:.2f}, {:.2f}, {:.1f}", v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    };
    fmt::print("  {:<12} {:>6} {:>24} {:>24} {:>9.2f} {:>9.2f}\n", p["name"].get<std::string>(), p["tiles"].get<int>(),
               point(p["from_mm"]), point(p["to_mm"]), p["seconds"].get<double>() / 3600.0, p["bytes"].get<double>() / 1e9);
  }
  fmt::print("  {:<12} {:>6} {:>24} {:>24} {:>9.2f} {:>9.2f}\n", "total", total.tiles, "", "", total.seconds / 3600.0,
             total.bytes / 1e9);
  fmt::print("Measure each path stitched and export its tiles with the encoder reading of each tile's centre; then\n"
             "  fvm calibrate --scan row.csv --scan column.csv --scan diagonal.csv --pixel-mm P --model 27 -o stage.json\n"
             "A second height (--heights -50,-40: a part with two levels, or on a spacer) lets the scans tell pitch and roll.\n");
  if (args.scan_dir.empty()) fmt::print("(give --scan-dir DIR to write the layouts)\n");
}

void RunPlan(const PlanArgs& args) {
  imaging::TilePlanOptions options;
  options.fov_mm = args.fov_mm > 0.0 ? args.fov_mm : imaging::FindLens(args.lens).fov_mm;
  options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.seconds_per_tile = args.seconds_per_tile;
  options.bytes_per_pixel = args.bytes_per_pixel;
  {
    const size_t x = args.tile_pixels.find('x');
    const std::string text = x == std::string::npos ? "" : args.tile_pixels.substr(0, x) + "," + args.tile_pixels.substr(x + 1);
    const auto wh = ParseNumbers(text, 2, "--tile-px " + args.tile_pixels, "1024x1024");
    options.pixels_x = static_cast<int>(wh[0]);
    options.pixels_y = static_cast<int>(wh[1]);
  }
  options.Check();
  if (args.calibration_scan) return RunCalibrationScanPlan(args, options);
  if (!args.features.empty() && !args.artefact.empty()) {
    throw InputError("give --features or --artefact, not both");
  }
  const std::vector<Feature> features = LoadFeatures(args);
  imaging::Region region;
  if (!args.region.empty()) {
    const auto r = ParseNumbers(args.region, 4, "--region", "--region 0,0,20,20 (x0,y0,x1,y1 in mm)");
    region = {r[0], r[1], r[2], r[3]};
  } else if (!features.empty()) {
    // The features' bounding box: the smallest region that holds every feature whole.
    region = {1e300, 1e300, -1e300, -1e300};
    for (const auto& f : features) {
      region.x0 = std::min(region.x0, f.centre_mm.x() - f.radius_mm);
      region.y0 = std::min(region.y0, f.centre_mm.y() - f.radius_mm);
      region.x1 = std::max(region.x1, f.centre_mm.x() + f.radius_mm);
      region.y1 = std::max(region.y1, f.centre_mm.y() + f.radius_mm);
    }
  } else {
    throw InputError("give --region x0,y0,x1,y1 (mm), or --features / --artefact to cover their bounding box");
  }
  const imaging::TileGrid grid = imaging::PlanStitchedGrid(region, options);
  const imaging::ScanCost stitched = imaging::EstimateScan(static_cast<int>(grid.tiles.size()), options);
  std::optional<imaging::StitchingFreePlan> free;
  std::optional<imaging::ScanCost> free_cost;
  if (!features.empty()) {
    free = imaging::PlanStitchingFree(grid, features);
    free_cost = imaging::EstimateScan(static_cast<int>(free->tiles.size()), options);
  }
  if (!args.free_output.empty() && !free) throw InputError("--free-layout needs --features or --artefact");

  const std::string describe =
      fmt::format("fvm tiles plan: field {} mm, overlap {:.4g} %, step {:.6f} mm; region {},{},{},{} mm; scan order "
                  "column by column from -X to +X, each from +Y to -Y; x,y = tile centre (mm)",
                  options.fov_mm, options.overlap * 100, grid.step_mm, region.x0, region.y0, region.x1, region.y1);
  if (!args.output.empty()) WriteFileAtomically(args.output, LayoutText(grid.tiles, describe + "; stitched"));
  if (!args.free_output.empty()) {
    WriteFileAtomically(args.free_output, LayoutText(free->tiles, describe + "; stitching-free"));
  }

  if (args.json) {
    nlohmann::ordered_json out;
    out["lens"] = args.fov_mm > 0.0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(args.lens);
    out["fov_mm"] = options.fov_mm;
    out["overlap"] = options.overlap;
    out["step_mm"] = grid.step_mm;
    out["region"] = {{"x0", region.x0}, {"y0", region.y0}, {"x1", region.x1}, {"y1", region.y1}};
    out["stitched"] = {{"rows", grid.rows},
                       {"cols", grid.cols},
                       {"tiles", stitched.tiles},
                       {"seconds", stitched.seconds},
                       {"bytes", stitched.bytes}};
    if (free) {
      nlohmann::ordered_json covers = nlohmann::ordered_json::array();
      for (const auto& c : free->covers) covers.push_back({{"id", c.feature_id}, {"tiles", c.tiles.size()}});
      out["stitching_free"] = {{"tiles", free_cost->tiles},
                               {"seconds", free_cost->seconds},
                               {"bytes", free_cost->bytes},
                               {"features", covers}};
    } else {
      out["stitching_free"] = nullptr;
    }
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("field {} mm, overlap {:.4g} % (step {:.4f} mm), region x {}..{} mm, y {}..{} mm\n", options.fov_mm,
             options.overlap * 100, grid.step_mm, region.x0, region.x1, region.y0, region.y1);
  fmt::print("first tile at lowest X, highest Y: centre ({:.4f}, {:.4f}) mm; columns -X to +X, each +Y to -Y\n\n",
             grid.tiles[0].centre_mm.x(), grid.tiles[0].centre_mm.y());
  fmt::print("{:<16}{:>8}{:>12}{:>12}\n", "layout", "tiles", "scan time", "data");
  fmt::print("{:<16}{:>8}{:>12}{:>12}   ({} x {})\n", "stitched", stitched.tiles, Duration(stitched.seconds),
             Bytes(stitched.bytes), grid.cols, grid.rows);
  if (free) {
    fmt::print("{:<16}{:>8}{:>12}{:>12}   ({} features)\n", "stitching-free", free_cost->tiles,
               Duration(free_cost->seconds), Bytes(free_cost->bytes), free->covers.size());
  }
  fmt::print("\ncosts assume {} s and {} x {} px of {} bytes per tile (--seconds-per-tile, --tile-pixels, "
             "--bytes-per-pixel)\n",
             options.seconds_per_tile, options.pixels_x, options.pixels_y, options.bytes_per_pixel);
}

}  // namespace

void RegisterTiles(CLI::App& app) {
  CLI::App* tiles = app.add_subcommand("tiles", "plan tile layouts with and without stitching");
  tiles->require_subcommand(1);
  tiles->footer("Example:\n  fvm tiles plan --lens 10x --artefact grid6x6 --overlap 13");

  auto plan_args = std::make_shared<PlanArgs>();
  CLI::App* plan = tiles->add_subcommand("plan", "the stitched tile grid of a region and the stitching-free tiles "
                                                 "that cover given features, with scan time and data volume");
  plan->add_option("--lens", plan_args->lens, "lens: 2.5x (5.63 mm field), 5x (2.82), 10x (1.62), 20x (0.81), "
                                              "50x (0.32), 100x (0.16)")
      ->capture_default_str();
  plan->add_option("--fov-mm", plan_args->fov_mm, "field of view in mm, instead of the lens table's")->check(Within(1e-3, 1e3, "mm"));
  AddHiddenAlias(plan, "--fov", plan_args->fov_mm, "--fov-mm");
  plan->add_option("--region", plan_args->region,
                   "x0,y0,x1,y1 in mm (default: the bounding box of the features)")
      ->check(NumbersCheck(4, "--region", "--region 0,0,20,20 (x0,y0,x1,y1 in mm)"));
  plan->add_option("--overlap", plan_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str();
  plan->add_option("--features", plan_args->features,
                   "centre export (CSV id,x,y,z[,radius], mm) of the features a stitching-free scan must cover");
  plan->add_option("--artefact", plan_args->artefact, "cover the calottes of a known artefact: grid6x6 or bar17, in "
                                                      "its own frame");
  plan->add_option("--radius-mm", plan_args->radius_mm, "feature radius in mm (overrides the file's or artefact's)")->check(Within(1e-3, 1e3, "mm"));
  AddHiddenAlias(plan, "--radius", plan_args->radius_mm, "--radius-mm");
  plan->add_option("--seconds-per-tile", plan_args->seconds_per_tile, "scan time per tile (s)")->check(Within(1e-3, 3600.0, "s"))->capture_default_str();
  plan->add_option("--tile-px", plan_args->tile_pixels, "pixels per tile, WxH")
      ->check(NumbersCheck(2, "--tile-px", "1024x1024", {16, 65536, "px", true}, 'x'))
      ->capture_default_str();
  AddHiddenAlias(plan, "--tile-pixels", plan_args->tile_pixels, "--tile-px");
  plan->add_option("--bytes-per-pixel", plan_args->bytes_per_pixel, "stored bytes per pixel (height + colour)")
      ->check(Count(1, 64))
      ->capture_default_str();
  plan->add_option("-o,--layout", plan_args->output, "write the stitched layout CSV file,row,col,x,y");
  plan->add_option("--free-layout", plan_args->free_output, "write the stitching-free layout CSV file,row,col,x,y");
  plan->add_flag("--calibration-scan", plan_args->calibration_scan,
                 "plan stitched calibration scans for fvm calibrate --scan instead: a row along X, a column along Y and "
                 "a diagonal through the travel's centre (any textured part; no artefact)");
  plan->add_option("--travel", plan_args->travel, "--calibration-scan: the stage travel WxH (mm), coordinates -W..0, -H..0")
      ->check(NumbersCheck(2, "--travel", "200x200", kTravelMm, 'x'))
      ->capture_default_str();
  plan->add_option("--length-mm", plan_args->length_mm, "--calibration-scan: length of each path")->check(Within(kStepMm))->capture_default_str();
  plan->add_option("--heights", plan_args->heights, "--calibration-scan: encoder z of each set of paths (mm), e.g. -50,-40")
      ->check(NumbersCheck(0, "--heights", "-50,-40"))
      ->capture_default_str();
  plan->add_option("--scan-dir", plan_args->scan_dir, "--calibration-scan: write each path's layout (file,row,col,x,y,z) here");
  plan->add_flag("--json", plan_args->json,
                 "print one JSON document {\"fov_mm\", \"overlap\", \"step_mm\", \"region\", \"stitched\": {\"rows\", "
                 "\"cols\", \"tiles\", \"seconds\", \"bytes\"}, \"stitching_free\": {\"tiles\", \"seconds\", \"bytes\", "
                 "\"features\"} or null}");
  plan->footer(
      "Tiles are squares of the field of view on a lattice of step field x (1 - overlap), anchored at the region's "
      "lowest X and highest Y, where the instrument starts; row 0 is the highest Y, column 0 the lowest X. The scan "
      "takes column after column from -X to +X, each from +Y to -Y. A stitching-free scan takes only the grid tiles "
      "that hold each feature whole.\n"
      "Example (the published 6 x 6 grid, 225 vs 49 tiles):\n  fvm tiles plan --lens 10x --artefact grid6x6 "
      "--overlap 13\n"
      "Calibration scans over 150 mm with the 5x lens:\n  fvm tiles plan --calibration-scan --lens 5x --overlap 25 "
      "--scan-dir scans");
  plan->callback([plan_args] { RunPlan(*plan_args); });

  AddTilesSynthesize(tiles);
  AddTilesSimulate(tiles);
}

}  // namespace fvm::cli
