// fvm tiles: plan tile layouts with and without stitching (imaging/tile_plan.h) and simulate the [Pérez 2019]
// stitching strategies on coordinates (artefacts/stitching_strategy.h) or on rendered tiles
// (artefacts/rendered_stitching_strategy.h).

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

std::string TileFile(int row, int col) { return fmt::format("tile_r{:03d}_c{:03d}.tif", row, col); }

std::string LayoutText(const std::vector<imaging::Tile>& tiles, const std::string& comment) {
  std::vector<imaging::TileLayoutEntry> entries;
  for (const auto& t : tiles) entries.push_back({TileFile(t.row, t.col), t.row, t.col, t.centre_mm, 0, std::nullopt});
  return "# " + comment + "\n" + imaging::FormatTileLayout(entries);
}

// A tile set for fvm stitch: every image as TileFile(row, col) in `directory`, and layout.csv headed by
// `comment` (its lines get '#'), with the stage positions of the tile centres when given. Returns the file names.
std::vector<std::string> WriteTileSet(const std::filesystem::path& directory,
                                      const std::vector<imaging::TileImage>& images,
                                      const std::vector<imaging::GridTile>& grid,
                                      const std::vector<Eigen::Vector2d>& stage_mm, imaging::TilePixelType type,
                                      const std::string& comment) {
  std::filesystem::create_directories(directory);
  std::vector<imaging::TileLayoutEntry> entries;
  std::vector<std::string> files;
  for (size_t i = 0; i < images.size(); ++i) {
    const imaging::GridTile& t = grid[i];
    files.push_back(TileFile(t.row, t.col));
    imaging::WriteTileImage(directory / files.back(), images[i], type);
    entries.push_back({files.back(), t.row, t.col,
                       stage_mm.empty() ? std::nullopt : std::optional<Eigen::Vector2d>(stage_mm[i]), 0, std::nullopt});
  }
  std::string header;
  std::stringstream lines(comment);
  for (std::string line; std::getline(lines, line);) header += "# " + line + "\n";
  WriteFileAtomically(directory / "layout.csv", header + imaging::FormatTileLayout(entries));
  return files;
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

struct SynthArgs {
  std::string output;
  int rows = 0, cols = 0, size = 256;  // 0: 3, or with --artefact as many as cover it
  std::string overlap = "0.2";
  double sigma_px = 1.5;
  int bits = 0;  // 0: 16, or with --artefact 32
  std::string artefact;
  std::string texture = "waves";
  bool size_given = false, overlap_given = false;
  std::uint64_t seed = 1;
};

// Height-map tiles of a known artefact (float TIFF, heights in mm, NaN where invalid), the layout with the stage
// positions the tiles were taken at, the true tile positions and the true calottes.
void RunSynthesizeHeights(const SynthArgs& args) {
  if (args.bits != 0 && args.bits != 32) throw InputError("--bits: height tiles are float (32)");
  artefacts::HeightTileOptions options;
  options.rows = args.rows;
  options.cols = args.cols;
  options.size = args.size;
  options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.position_sigma_px = args.sigma_px;
  options.seed = args.seed;
  artefacts::SynthesizedHeightTiles tiles;
  try {
    tiles = artefacts::SynthesizeHeightTiles(artefacts::KnownArtefact(args.artefact), options);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const std::filesystem::path dir(args.output);
  const double pixel = tiles.surface.map.dx_mm;
  const std::vector<std::string> files = WriteTileSet(
      dir, tiles.images, tiles.tiles, tiles.nominal_centre_mm, imaging::TilePixelType::kFloat,
      fmt::format("fvm tiles synthesize --artefact {} --seed {}: {} height tiles of {} px, {} mm per px; x,y = stage "
                  "positions of the tile centres (mm). Stitch with:\nfvm stitch --layout layout.csv --overlap {:g} "
                  "--pixel-mm {} -o positions.csv --mosaic mosaic.x3p",
                  args.artefact, args.seed, tiles.images.size(), args.size, pixel, options.overlap * 100, pixel));
  std::string truth = "file,x,y,x_mm,y_mm\n";
  for (size_t i = 0; i < files.size(); ++i) {
    const Eigen::Vector2d error = tiles.truth_px[i] - tiles.tiles[i].nominal_px;
    truth += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y(),
                         tiles.nominal_centre_mm[i].x() + error.x() * pixel,
                         tiles.nominal_centre_mm[i].y() - error.y() * pixel);
  }
  artefacts::CentreExport calottes;
  calottes.comments.push_back(fmt::format("fvm tiles synthesize --artefact {} --seed {}: the true calottes (mm)",
                                          args.artefact, args.seed));
  for (const auto& c : tiles.surface.truth) {
    artefacts::CentreRecord record;
    record.id = c.id;
    record.position = c.centre;
    record.radius_mm = c.radius_mm;
    calottes.centres.push_back(record);
  }
  artefacts::WriteCentreExport(dir / "calottes.csv", calottes);
  WriteFileAtomically(dir / "truth.csv", truth);
  fmt::print("{} height tiles of {} ({} x {} px, {} mm per px), layout.csv, truth.csv (true positions) and "
             "calottes.csv (true calottes) written to {}\n",
             tiles.images.size(), args.artefact, args.size, args.size, pixel, args.output);
}

// What a real microscope set of a sparse sample looks like (artefacts/simulation/sparse_tile_synthesis.h): 16-bit
// blobs on a smooth background, thin overlaps, a stage with a systematic step error and a drift.
void RunSynthesizeSparse(const SynthArgs& args) {
  if (args.bits != 0 && args.bits != 16) throw InputError("--bits: sparse tiles are 16-bit counts");
  artefacts::SparseTileOptions options;
  if (args.rows > 0) options.rows = args.rows;
  if (args.cols > 0) options.cols = args.cols;
  if (args.size_given) options.width = options.height = args.size;
  if (args.overlap_given) options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.repeatability_px = args.sigma_px;
  options.seed = args.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize --texture sparse: ") + e.what());
  }
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeSparseTiles(options);
  const std::vector<std::string> files = WriteTileSet(
      args.output, tiles.images, tiles.tiles, {}, imaging::TilePixelType::kUint16,
      fmt::format("fvm tiles synthesize --texture sparse --seed {}: {} x {} tiles of {} x {} px, overlap {}; the "
                  "stage steps {:+g}, {:+g} px per column and {:+g}, {:+g} px per row off the nominal, "
                  "repeatability {} px",
                  args.seed, options.rows, options.cols, options.width, options.height, options.overlap,
                  options.east_step_error_px.x(), options.east_step_error_px.y(), options.south_step_error_px.x(),
                  options.south_step_error_px.y(), options.repeatability_px));
  std::string truth = "file,x,y\n";
  for (size_t i = 0; i < files.size(); ++i) {
    truth += fmt::format("{},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y());
  }
  WriteFileAtomically(std::filesystem::path(args.output) / "truth.csv", truth);
  fmt::print("{} sparse tiles of {} x {} px (overlap {:g} %), layout.csv and truth.csv (true positions, px) written "
             "to {}\n",
             tiles.images.size(), options.width, options.height, options.overlap * 100, args.output);
}

void RunSynthesize(const SynthArgs& args) {
  if (!args.artefact.empty() && args.texture != "waves") {
    throw InputError("--texture " + args.texture + " and --artefact: give one of them");
  }
  if (!args.artefact.empty()) return RunSynthesizeHeights(args);
  if (args.texture == "sparse") return RunSynthesizeSparse(args);
  if (args.texture != "waves") throw InputError("--texture " + args.texture + ": give waves or sparse");
  artefacts::TileSynthesisOptions options;
  options.rows = args.rows > 0 ? args.rows : 3;
  options.cols = args.cols > 0 ? args.cols : 3;
  options.width = options.height = args.size;
  options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.position_sigma_px = args.sigma_px;
  options.seed = args.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const int bits = args.bits == 0 ? 16 : args.bits;
  if (bits != 8 && bits != 16 && bits != 32) throw InputError("--bits: 8, 16 or 32 (float)");
  if (bits == 8) options.camera.level = 120.0, options.camera.contrast = 25.0;  // 0..255 with the vignetting
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(options);
  const std::vector<std::string> files = WriteTileSet(
      args.output, tiles.images, tiles.tiles, {},
      bits == 8    ? imaging::TilePixelType::kUint8
      : bits == 16 ? imaging::TilePixelType::kUint16
                   : imaging::TilePixelType::kFloat,
      fmt::format("fvm tiles synthesize --seed {}: {} x {} tiles of {} px, overlap {}", args.seed, options.rows,
                  options.cols, args.size, options.overlap));
  std::string truth = "file,x,y\n";
  for (size_t i = 0; i < files.size(); ++i) {
    truth += fmt::format("{},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y());
  }
  WriteFileAtomically(std::filesystem::path(args.output) / "truth.csv", truth);
  fmt::print("{} tiles, layout.csv and truth.csv (true positions, px) written to {}\n", tiles.images.size(),
             args.output);
}

struct StrategyArgs {
  std::string calibration;
  std::string lens = "10x";
  double overlap = 0.2;
  std::vector<double> from{-154.5487, -115.4767, -50.3624};  // [Pérez 2019] Table 1, case a, calotte 1
  std::vector<double> to{-134.5409, -115.4371, -50.4457};    // ... calotte 6
  bool render = false;
  std::string tiles_output;
  int tile_px = artefacts::RenderedStrategyOptions{}.tile_px;
  std::uint64_t seed = 1;
  bool json = false;
};

// The rendered row as a tile set for fvm stitch: 16-bit TIFFs and a layout whose x, y are the encoder readings of
// the tile centres, so that stitching them with the pixel size reproduces case a.
void WriteRenderedRow(const artefacts::RenderedStrategies& row, const artefacts::RenderedStrategyOptions& options,
                      const std::filesystem::path& directory) {
  std::vector<imaging::GridTile> grid;
  for (size_t i = 0; i < row.images.size(); ++i) grid.push_back({0, static_cast<int>(i), Eigen::Vector2d::Zero()});
  WriteTileSet(directory, row.images, grid, row.encoder_centres_mm, imaging::TilePixelType::kUint16,
               fmt::format("fvm tiles simulate --render --seed {}: the row of {} tiles of {} px, {:.6f} mm per px, "
                           "x,y = encoder readings of the tile centres (mm). Stitch with:\nfvm stitch --layout "
                           "layout.csv --overlap {:g} --pixel-mm {:.9g} -o positions.csv",
                           options.seed, row.images.size(), options.tile_px, row.pixel_mm,
                           options.geometry.overlap * 100, row.pixel_mm));
}

void RunStrategies(const StrategyArgs& args) {
  imaging::SetImagingThreads(ThreadCount());  // --render registers tiles on OpenCV's pool
  const stage::Calibration cal = stage::ReadCalibration(args.calibration);
  artefacts::RenderedStrategyOptions options;
  options.geometry.fov_mm = imaging::FindLens(args.lens).fov_mm;
  options.geometry.overlap = args.overlap > 1.0 ? args.overlap / 100.0 : args.overlap;
  options.tile_px = args.tile_px;
  options.seed = args.seed;
  const Eigen::Vector3d first(args.from[0], args.from[1], args.from[2]);
  const Eigen::Vector3d last(args.to[0], args.to[1], args.to[2]);
  if (!args.tiles_output.empty() && !args.render) throw InputError("--tiles needs --render");
  std::vector<artefacts::StrategyResult> results;
  std::optional<artefacts::RenderedStrategies> rendered;
  try {
    if (args.render) {
      if (!args.json) fmt::print(stderr, "rendering and registering the row's tiles ...\n");
      rendered = artefacts::SimulateRenderedStrategies(cal.layout, cal.values, first, last, options);
      for (const artefacts::RenderedStrategyResult& c : rendered->cases) results.push_back(c.coordinates);
    } else {
      results = artefacts::SimulateStitchingStrategies(cal.layout, cal.values, first, last, options.geometry);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles simulate: ") + e.what());
  }
  if (!args.tiles_output.empty()) WriteRenderedRow(*rendered, options, args.tiles_output);
  // The published differences ([Pérez 2019] Table 1, 6 x 6 grid, 10x lens, calottes 1 and 6), for comparison.
  const std::map<char, double> published = {{'b', -14.6}, {'c', -1.5}, {'d', -8.9}, {'e', -14.8}, {'f', -15.0}};
  nlohmann::ordered_json doc;
  doc["calibration"] = args.calibration;
  doc["fov_mm"] = options.geometry.fov_mm;
  doc["overlap"] = options.geometry.overlap;
  if (rendered) {
    doc["rendered"] = {{"tile_px", options.tile_px},
                       {"pixel_um", rendered->pixel_mm * 1e3},
                       {"row_tiles", rendered->row_tiles},
                       {"pair_rms_px", rendered->pair_rms_px},
                       {"rejected_pairs", rendered->rejected_pairs},
                       {"seed", options.seed}};
  }
  for (size_t k = 0; k < results.size(); ++k) {
    const artefacts::StrategyResult& r = results[k];
    nlohmann::ordered_json c = {{"case", std::string(1, r.id)}, {"description", r.description},
                                {"tiles", r.tiles},           {"encoder_tiles", r.encoder_tiles},
                                {"distance_mm", r.distance_mm}, {"diff_um", r.distance_error_um}};
    if (rendered) {
      const artefacts::RenderedStrategyResult& g = rendered->cases[k];
      c["rendered"] = {{"encoder_tiles", g.result.encoder_tiles}, {"distance_mm", g.result.distance_mm},
                       {"diff_um", g.result.distance_error_um},  {"pairs", g.pairs},
                       {"accepted_pairs", g.accepted_pairs}};
    }
    doc["cases"].push_back(c);
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("stitching strategies over {:.3f} mm with the {} lens ({} mm field, {:.0f} % overlap), stage model {} "
             "from {}\n",
             (last - first).norm(), args.lens, options.geometry.fov_mm, options.geometry.overlap * 100, cal.model,
             args.calibration);
  if (rendered) {
    fmt::print("rendered: {} tiles of {} px ({:.3f} um / px), neighbour pairs registered to {:.3f} px rms ({:.3f} um), "
               "{} rejected; seed {}\n",
               rendered->row_tiles, options.tile_px, rendered->pixel_mm * 1e3, rendered->pair_rms_px,
               rendered->pair_rms_px * rendered->pixel_mm * 1e3, rendered->rejected_pairs, options.seed);
  }
  fmt::print("\n  {:<4} {:<36} {:>5} {:>13} {:>10} {:>12} {:>14}\n", "case", "strategy", "tiles", "distance mm",
             "diff um", rendered ? "rendered um" : "", "published um");
  for (size_t k = 0; k < results.size(); ++k) {
    const artefacts::StrategyResult& r = results[k];
    const auto p = published.find(r.id);
    fmt::print("  {:<4} {:<36} {:>5} {:>13.4f} {:>10.1f} {:>12} {:>14}\n", r.id, r.description, r.tiles,
               r.distance_mm, r.distance_error_um,
               rendered ? fmt::format("{:.1f}", rendered->cases[k].result.distance_error_um) : "",
               p == published.end() ? "-" : fmt::format("{:.1f}", p->second));
  }
  fmt::print("\n  A tile that cannot be registered to its neighbour falls back to the encoders and carries the stage "
             "error there;\n  the error grows with the distance from the first tile to the last such tile.\n");
  if (rendered) {
    fmt::print("  'rendered' comes from images: tiles rendered where the stage really is, registered, and the calottes "
               "fitted in\n  their tiles; it differs from 'diff' by the registration and fit noise.\n");
  }
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

  auto synth_args = std::make_shared<SynthArgs>();
  CLI::App* synth = tiles->add_subcommand(
      "synthesize", "synthetic overlapping tiles with known positions, for trying fvm stitch");
  synth->add_option("-o,--output", synth_args->output, "directory for the tiles, layout.csv and truth.csv")
      ->required();
  synth->add_option("--rows", synth_args->rows, "tile rows (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--cols", synth_args->cols, "tile columns (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--tile-px", synth_args->size, "tile width and height (px; --texture sparse: 245 x 183)")
      ->check(Count(16, 8192))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->size_given = true; });
  AddHiddenAlias(synth, "--size", synth_args->size, "--tile-px")->each([synth_args](const std::string&) {
    synth_args->size_given = true;
  });
  synth->add_option("--overlap", synth_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %; --texture sparse: 6)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->overlap_given = true; });
  synth->add_option("--stage-sigma-px", synth_args->sigma_px,
                    "standard deviation of the stage error per axis (px; with --texture sparse the repeatability "
                    "on top of the systematic step error)")
      ->check(Within(0.0, 1e3, "px"))
      ->capture_default_str();
  synth->add_option("--texture", synth_args->texture,
                    "waves: a dense random texture; sparse: 16-bit blobs on a smooth background with shot noise, "
                    "5 x 5 tiles, a stage that steps 1.2 px long and drifts 4 px per column (like a real "
                    "microscope set of a sparse sample)")
      ->capture_default_str();
  AddHiddenAlias(synth, "--stage-error", synth_args->sigma_px, "--stage-sigma-px");
  synth->add_option("--bits", synth_args->bits, "pixel type: 8, 16 (integer, the default) or 32 (float)")->check(Count(8, 32));
  synth->add_option("--artefact", synth_args->artefact,
                    "height-map tiles of grid6x6 or bar17 instead (float, mm, 10 um pixels, NaN on steep flanks), "
                    "with calottes.csv, the true calottes");
  synth->add_option("--seed", synth_args->seed, "random seed")->check(Within(kSeed))->capture_default_str();
  synth->footer("Tiles are cut from one random texture with 30 % vignetting and 3 % noise; truth.csv holds the "
                "true top-left corners, the first tile at 0,0. With --artefact they are cut from one height map of "
                "the artefact (0.5 um of roughness, 0.1 um of noise per tile) and the layout holds the stage "
                "positions: fvm tiles synthesize --artefact grid6x6 -o g && cd g && fvm stitch --layout layout.csv "
                "--overlap 20 --pixel-mm 0.01 -o p.csv --mosaic m.x3p && fvm fit m.x3p --artefact grid6x6 -o c.csv\n"
                "Example:\n  fvm tiles synthesize -o demo --rows 3 --cols 4 --tile-px 512 --overlap 20 --seed 1");
  synth->callback([synth_args] { RunSynthesize(*synth_args); });

  auto strategy_args = std::make_shared<StrategyArgs>();
  CLI::App* strategies = tiles->add_subcommand(
      "simulate", "the end-to-end distance error of the six stitching strategies of [Pérez 2019] under a stage model");
  strategies->add_option("--calibration", strategy_args->calibration, "stage model: a file written by 'fvm calibrate -o'")
      ->required();
  strategies->add_option("--lens", strategy_args->lens, "lens (field of view from the lens table)")->capture_default_str();
  strategies->add_option("--overlap", strategy_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str();
  strategies->add_option("--from", strategy_args->from, "first calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 1)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_option("--to", strategy_args->to, "last calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 6)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_flag("--render", strategy_args->render,
                       "also render the row's tiles where the stage really puts them, register them as fvm stitch "
                       "does and fit the calottes in their tiles (a few seconds)");
  strategies->add_option("--tile-px", strategy_args->tile_px, "with --render: pixels across a tile")
      ->check(Count(16, 8192))
      ->capture_default_str();
  strategies->add_option("--tiles", strategy_args->tiles_output,
                         "with --render: write the row's tiles (16-bit TIFF) and layout.csv (encoder positions) to "
                         "this directory, ready for fvm stitch");
  strategies->add_option("--seed", strategy_args->seed, "with --render: seed of the texture and the noise")
      ->check(Within(kSeed))
      ->capture_default_str();
  strategies->add_flag("--json", strategy_args->json,
                       "print {\"cases\": [{\"case\", \"description\", \"tiles\", \"encoder_tiles\", "
                       "\"distance_mm\", \"diff_um\"[, \"rendered\": {\"encoder_tiles\", \"distance_mm\", "
                       "\"diff_um\", \"pairs\", \"accepted_pairs\"}]}][, \"rendered\": {\"tile_px\", "
                       "\"pixel_um\", \"row_tiles\", \"pair_rms_px\", \"rejected_pairs\", \"seed\"}]}");
  strategies->footer("Cases: a all stitched; b only the end tiles; c the tile after the first missing; d a middle "
                     "tile missing; e the tile before the last missing; f every other tile missing ([Pérez 2019] Tables 1-2).\n"
                     "Example:\n  fvm calibrate samples/bar17 --model 27 -o stage.json && fvm tiles simulate "
                     "--calibration stage.json --lens 10x --overlap 20 --render");
  strategies->callback([strategy_args] { RunStrategies(*strategy_args); });
}

}  // namespace fvm::cli
