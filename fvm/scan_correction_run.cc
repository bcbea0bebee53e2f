#include "fvm/scan_correction_run.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/grid_resampling.h"
#include "imaging/height_map.h"
#include "imaging/io/point_cloud_io.h"
#include "imaging/io/tile_layout.h"
#include "imaging/point_cloud.h"
#include "workflows/correct_scan.h"

namespace fvm::cli {
namespace {

std::vector<imaging::PointField> UncertaintyFields(const std::vector<Eigen::Vector3d>& u) {
  std::vector<imaging::PointField> fields = {{"u_x", {}}, {"u_y", {}}, {"u_z", {}}};
  for (auto& f : fields) f.values.reserve(u.size());
  for (const Eigen::Vector3d& v : u) {
    for (int k = 0; k < 3; ++k) fields[static_cast<std::size_t>(k)].values.push_back(v[k]);
  }
  return fields;
}

// Beside a height map, which has no place for them: x,y (the node) and u_x,u_y,u_z (mm) of every valid node.
std::filesystem::path SideCsvPath(const std::filesystem::path& output) {
  std::filesystem::path side = output;
  side.replace_extension(".uncertainty.csv");
  return side;
}

std::string FrameName(const ScanCorrectionArgs& args) {
  if (!args.options.first_tile_frame) return "stage";
  return fmt::format("first-tile ({})", stage::StitchedFrameName(*args.options.first_tile_frame));
}

nlohmann::json FrameJson(const ScanCorrectionArgs& args, const std::optional<Eigen::Vector3d>& first_tile) {
  nlohmann::json doc = {{"frame", args.options.first_tile_frame ? "first-tile" : "stage"}};
  if (first_tile) {
    const Eigen::Vector3d& a = *first_tile;
    doc["stitched_frame"] = stage::StitchedFrameName(*args.options.first_tile_frame);
    doc["first_tile_mm"] = {a.x(), a.y(), a.z()};
  }
  const Eigen::Vector3d& o = args.options.origin_mm;
  doc["origin_mm"] = {o.x(), o.y(), o.z()};
  return doc;
}

workflows::ScanCorrectionJob Job(const ScanCorrectionArgs& args) {
  return {args.calibration, args.options, args.extrapolate, args.threads};
}

void RunOneScan(const ScanCorrectionArgs& args, const stage::Calibration& cal) {
  const std::optional<imaging::SurfaceFormat> out_format = imaging::SurfaceFormatOfName(args.output);
  if (!out_format) {
    throw InputError(fmt::format("{}: unknown output type; write a cloud (.ply, .pcd, .xyz) or, with --resample, a "
                                 "height map (.x3p, .al3d, .tif)", args.output));
  }
  const bool map_out = !imaging::IsPointCloudFormat(*out_format);
  imaging::Surface surface = imaging::ReadSurface(args.input, args.read);
  const bool map_in = surface.height_map.has_value();
  if (map_out && !(args.resample_mm > 0.0)) {
    throw InputError(fmt::format(
        "{}: a corrected scan's points are no longer on a grid; give --resample PIXEL_MM (e.g. {}) for a height map, "
        "or write a cloud (.ply, .pcd, .xyz)",
        args.output, map_in ? FormatShortest(surface.height_map->dx_mm) : std::string("0.01")));
  }
  if (args.resample_mm > 0.0 && !map_in && !surface.cloud->IsOrganised()) {
    throw InputError(args.input + ": only a height map or an organised cloud can be resampled on a grid; an "
                                  "unorganised cloud has no cells to interpolate in: leave out --resample");
  }
  imaging::PointCloud cloud = map_in ? imaging::HeightMapToCloud(*surface.height_map) : std::move(*surface.cloud);
  surface = {};  // the map's heights are in the cloud now: hold one copy
  workflows::CorrectedCloud corrected = workflows::CorrectCloud(cloud, cal, Job(args), args.input, !map_out);
  const stage::ScanCorrector& corrector = corrected.corrector;
  const stage::ScanCorrectionSummary& summary = corrected.summary;
  const std::vector<std::size_t>& outside = corrected.outside;
  std::vector<Eigen::Vector3d>& u = corrected.u;

  std::string uncertainty_where;
  if (!map_out && args.resample_mm > 0.0) {
    cloud = imaging::HeightMapToCloud(imaging::ResampleOnGrid(cloud, args.resample_mm, args.input));
    u = workflows::UncertaintiesAt(corrector, cloud.points);
  }
  if (map_out) {
    const imaging::HeightMap map = imaging::ResampleOnGrid(cloud, args.resample_mm, args.input);
    // The uncertainty field is smooth over a pixel: each node gets that of the point at its own position.
    std::string csv = fmt::format("# standard uncertainties of {} (fvm correct with {}, model {}), mm\nx,y,u_x,u_y,u_z\n",
                                  args.output, args.calibration, cal.model);
    for (int iy = 0; iy < map.size_y; ++iy) {
      for (int ix = 0; ix < map.size_x; ++ix) {
        if (!std::isfinite(map.at(ix, iy))) continue;
        const Eigen::Vector3d node(map.x0_mm + ix * map.dx_mm, map.y0_mm + iy * map.dy_mm, map.at(ix, iy));
        const Eigen::Vector3d s = corrector.Correct(node).covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
        csv += FormatShortest(node.x()) + "," + FormatShortest(node.y()) + "," + FormatFixed(s.x(), 7) + "," +
               FormatFixed(s.y(), 7) + "," + FormatFixed(s.z(), 7) + "\n";
      }
    }
    uncertainty_where = SideCsvPath(args.output).string();
    WriteFileAtomically(uncertainty_where, csv);
    imaging::WriteHeightMap(args.output, map);
  } else {
    uncertainty_where = std::string(*out_format == imaging::SurfaceFormat::kXyz ? "columns" : "properties") +
                        " u_x, u_y, u_z of " + args.output;
    const std::string comment = fmt::format("corrected by fvm with {} (model {}); frame: {}", args.calibration, cal.model,
                                            FrameName(args));
    imaging::WritePointCloud(args.output, cloud, UncertaintyFields(u), comment);
  }

  if (args.json) {
    nlohmann::json doc = FrameJson(args, corrector.first_tile() ? std::optional<Eigen::Vector3d>(corrector.first_tile()->frame().first_tile) : std::nullopt);
    doc["input"] = args.input;
    doc["output"] = args.output;
    doc["points"] = summary.corrected + summary.invalid;
    doc["corrected"] = summary.corrected;
    doc["invalid"] = summary.invalid;
    doc["outside_travel"] = outside.size();
    doc["largest_shift_um"] = summary.largest_shift_mm * 1e3;
    doc["uncertainty"] = uncertainty_where;
    if (map_out || args.resample_mm > 0.0) doc["resample_mm"] = args.resample_mm;
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("corrected {} points of {} with model {} in the {} frame (each point by the model at its own stage "
             "coordinates); largest shift {:.2f} um",
             summary.corrected, args.input, cal.model, FrameName(args), summary.largest_shift_mm * 1e3);
  if (summary.invalid > 0) fmt::print("; {} invalid points (NaN or infinite) skipped", summary.invalid);
  if (!outside.empty()) fmt::print("; {} points outside the calibrated travel extrapolated", outside.size());
  fmt::print("\n  written to {}; standard uncertainties in {}\n", args.output, uncertainty_where);
}

void RunLayout(const ScanCorrectionArgs& args, const stage::Calibration& cal) {
  const imaging::TileLayout layout = imaging::ReadTileLayout(args.layout);
  const std::filesystem::path base = std::filesystem::path(args.layout).parent_path();
  std::vector<imaging::Surface> tiles;
  std::vector<imaging::PointCloud> clouds;
  std::vector<workflows::TileInput> inputs;
  for (const imaging::TileLayoutEntry& entry : layout.tiles) {
    if (!entry.stage_mm) {
      throw InputError(fmt::format("{}:{}: tile {} has no stage position; per-tile correction needs x,y (mm) of "
                                   "every tile", args.layout, entry.line, entry.file));
    }
    imaging::Surface tile = imaging::ReadSurface(base / entry.file, args.read);
    clouds.push_back(tile.height_map ? imaging::HeightMapToCloud(*tile.height_map) : *tile.cloud);
    inputs.push_back({entry.file, (base / entry.file).string(), *entry.stage_mm, nullptr});
    tiles.push_back(std::move(tile));
  }
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i].cloud = &clouds[i];
  const workflows::TileCorrection corrected = workflows::CorrectTiles(inputs, cal, Job(args), args.layout);
  const std::vector<workflows::TileShift>& shifts = corrected.tiles;
  const std::vector<std::size_t>& outside = corrected.outside;
  const double largest_per_point = corrected.largest_per_point_mm;
  ScanCorrectionArgs stage_args = args;
  stage_args.options.origin_mm.setZero();  // layout positions are stage positions

  const std::filesystem::path out(args.output);
  std::filesystem::create_directories(out);
  std::string csv = fmt::format("# per-tile correction by fvm with {} (model {}), frame {}: each tile moved by "
                                "d (um), the model at its stage position; per_point_um: how far the per-point "
                                "correction departs from d at the tile's corners\n",
                                args.calibration, cal.model, FrameName(args));
  csv += "file,x,y,z,dx_um,dy_um,dz_um,u_x_um,u_y_um,u_z_um,per_point_um\n";
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const workflows::TileShift& t = shifts[i];
    imaging::Surface& tile = tiles[i];
    const std::filesystem::path target = out / std::filesystem::path(t.file).filename();
    if (tile.height_map) {
      imaging::HeightMap& map = *tile.height_map;
      map.x0_mm += t.shift.x();
      map.y0_mm += t.shift.y();
      for (double& z : map.z_mm) z += t.shift.z();
      imaging::WriteHeightMap(target, map);
    } else {
      for (Eigen::Vector3d& p : tile.cloud->points) p += t.shift;
      imaging::WritePointCloud(target, *tile.cloud);
    }
    csv += CsvLine({t.file, FormatFixed(t.centre.x(), 6), FormatFixed(t.centre.y(), 6), FormatFixed(t.centre.z(), 6),
                    FormatFixed(t.shift.x() * 1e3, 4), FormatFixed(t.shift.y() * 1e3, 4), FormatFixed(t.shift.z() * 1e3, 4),
                    FormatFixed(t.u.x() * 1e3, 4), FormatFixed(t.u.y() * 1e3, 4), FormatFixed(t.u.z() * 1e3, 4),
                    FormatFixed(t.per_point_mm * 1e3, 4)});
  }
  WriteFileAtomically(out / "shifts.csv", csv);
  if (args.json) {
    nlohmann::json doc = FrameJson(stage_args, corrected.first_tile_mm);
    doc["layout"] = args.layout;
    doc["output"] = args.output;
    doc["tiles"] = nlohmann::json::array();
    for (const workflows::TileShift& t : shifts) {
      doc["tiles"].push_back({{"file", t.file},
                              {"shift_um", {t.shift.x() * 1e3, t.shift.y() * 1e3, t.shift.z() * 1e3}},
                              {"u_um", {t.u.x() * 1e3, t.u.y() * 1e3, t.u.z() * 1e3}},
                              {"per_point_um", t.per_point_mm * 1e3}});
    }
    doc["outside_travel"] = outside.size();
    doc["largest_per_point_um"] = largest_per_point * 1e3;
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("corrected {} tiles of {} with model {} in the {} frame, each by one shift at its stage position; "
             "per-point correction would differ by up to {:.3f} um at the tiles' corners\n  written to {} "
             "(shifts.csv lists every tile)\n",
             shifts.size(), args.layout, cal.model, FrameName(args), largest_per_point * 1e3, args.output);
}

}  // namespace

void RunScanCorrection(const ScanCorrectionArgs& args, const stage::Calibration& calibration) {
  if (!args.layout.empty()) {
    RunLayout(args, calibration);
  } else {
    RunOneScan(args, calibration);
  }
}

}  // namespace fvm::cli
