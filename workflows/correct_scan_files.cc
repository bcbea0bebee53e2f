#include "workflows/correct_scan_files.h"

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

namespace fvm::workflows {
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

// The stage library's options: the frame asked and the stage position of the file's origin.
stage::ScanCorrectionOptions StageOptions(const CorrectOptions& o) {
  stage::ScanCorrectionOptions options;
  if (o.origin_mm) options.origin_mm = *o.origin_mm;
  if (o.frame == "first-tile") options.first_tile_frame = stage::ParseStitchedFrame(o.stitched_frame);
  return options;
}

std::string FrameName(const stage::ScanCorrectionOptions& options) {
  if (!options.first_tile_frame) return "stage";
  return fmt::format("first-tile ({})", stage::StitchedFrameName(*options.first_tile_frame));
}

nlohmann::json FrameJson(const stage::ScanCorrectionOptions& options, const std::optional<Eigen::Vector3d>& first_tile) {
  nlohmann::json doc = {{"frame", options.first_tile_frame ? "first-tile" : "stage"}};
  if (first_tile) {
    const Eigen::Vector3d& a = *first_tile;
    doc["stitched_frame"] = stage::StitchedFrameName(*options.first_tile_frame);
    doc["first_tile_mm"] = {a.x(), a.y(), a.z()};
  }
  const Eigen::Vector3d& o = options.origin_mm;
  doc["origin_mm"] = {o.x(), o.y(), o.z()};
  return doc;
}

ScanCorrectionJob Job(const CorrectOptions& o) { return {o.calibration, StageOptions(o), o.extrapolate, o.threads}; }

// Beside a corrected height map: x,y and u_x,u_y,u_z (mm) of every valid node. The uncertainty field is smooth over
// a pixel: each node gets that of the point at its own position.
void WriteNodeUncertainties(const CorrectOptions& o, const stage::Calibration& cal, const stage::ScanCorrector& corrector,
                            const imaging::HeightMap& map, const std::filesystem::path& path) {
  std::string csv = fmt::format("# standard uncertainties of {} (fvm correct with {}, model {}), mm\nx,y,u_x,u_y,u_z\n",
                                o.output, o.calibration, cal.model);
  for (int iy = 0; iy < map.size_y; ++iy) {
    for (int ix = 0; ix < map.size_x; ++ix) {
      if (!std::isfinite(map.at(ix, iy))) continue;
      const Eigen::Vector3d node(map.x0_mm + ix * map.dx_mm, map.y0_mm + iy * map.dy_mm, map.at(ix, iy));
      const Eigen::Vector3d s = corrector.Correct(node).covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      csv += FormatShortest(node.x()) + "," + FormatShortest(node.y()) + "," + FormatFixed(s.x(), 7) + "," +
             FormatFixed(s.y(), 7) + "," + FormatFixed(s.z(), 7) + "\n";
    }
  }
  WriteFileAtomically(path, csv);
}

// The scan as the options read it, refused before any work when the output cannot be what it asks.
imaging::PointCloud ReadScan(const CorrectOptions& o, bool map_out) {
  imaging::Surface surface = imaging::ReadSurface(o.input, o.read);
  const bool map_in = surface.height_map.has_value();
  if (map_out && !(o.resample_mm > 0.0)) {
    throw InputError(fmt::format(
        "{}: a corrected scan's points are no longer on a grid; give --resample PIXEL_MM (e.g. {}) for a height map, "
        "or write a cloud (.ply, .pcd, .xyz)",
        o.output, map_in ? FormatShortest(surface.height_map->dx_mm) : std::string("0.01")));
  }
  if (o.resample_mm > 0.0 && !map_in && !surface.cloud->IsOrganised()) {
    throw InputError(o.input + ": only a height map or an organised cloud can be resampled on a grid; an "
                               "unorganised cloud has no cells to interpolate in: leave out --resample");
  }
  return map_in ? imaging::HeightMapToCloud(*surface.height_map) : std::move(*surface.cloud);
}

}  // namespace

CorrectedFiles CorrectScanFile(const CorrectOptions& o, const stage::Calibration& cal) {
  const std::optional<imaging::SurfaceFormat> out_format = imaging::SurfaceFormatOfName(o.output);
  if (!out_format) {
    throw InputError(fmt::format("{}: unknown output type; write a cloud (.ply, .pcd, .xyz) or, with --resample, a "
                                 "height map (.x3p, .al3d, .tif)", o.output));
  }
  const bool map_out = !imaging::IsPointCloudFormat(*out_format);
  imaging::PointCloud cloud = ReadScan(o, map_out);
  CorrectedCloud corrected = CorrectCloud(cloud, cal, Job(o), o.input, !map_out);
  const stage::ScanCorrector& corrector = corrected.corrector;
  const stage::ScanCorrectionSummary& summary = corrected.summary;
  const stage::ScanCorrectionOptions options = StageOptions(o);
  std::vector<Eigen::Vector3d>& u = corrected.u;

  std::string uncertainty_where;
  if (!map_out && o.resample_mm > 0.0) {
    cloud = imaging::HeightMapToCloud(imaging::ResampleOnGrid(cloud, o.resample_mm, o.input));
    u = UncertaintiesAt(corrector, cloud.points);
  }
  if (map_out) {
    const imaging::HeightMap map = imaging::ResampleOnGrid(cloud, o.resample_mm, o.input);
    uncertainty_where = SideCsvPath(o.output).string();
    WriteNodeUncertainties(o, cal, corrector, map, uncertainty_where);
    imaging::WriteHeightMap(o.output, map);
  } else {
    uncertainty_where = std::string(*out_format == imaging::SurfaceFormat::kXyz ? "columns" : "properties") +
                        " u_x, u_y, u_z of " + o.output;
    const std::string comment =
        fmt::format("corrected by fvm with {} (model {}); frame: {}", o.calibration, cal.model, FrameName(options));
    imaging::WritePointCloud(o.output, cloud, UncertaintyFields(u), comment);
  }

  CorrectedFiles out;
  nlohmann::json doc;  // sorted keys, as the command has always printed them
  doc = FrameJson(options, corrector.first_tile() ? std::optional<Eigen::Vector3d>(corrector.first_tile()->frame().first_tile)
                                                  : std::nullopt);
  doc["points"] = summary.corrected + summary.invalid;
  doc["corrected"] = summary.corrected;
  doc["invalid"] = summary.invalid;
  doc["outside_travel"] = corrected.outside.size();
  doc["largest_shift_um"] = summary.largest_shift_mm * 1e3;
  doc["uncertainty"] = uncertainty_where;
  if (map_out || o.resample_mm > 0.0) doc["resample_mm"] = o.resample_mm;
  std::string& text = out.summary.text;
  text = fmt::format("corrected {} points of {} with model {} in the {} frame (each point by the model at its own stage "
                     "coordinates); largest shift {:.2f} um",
                     summary.corrected, o.input, cal.model, FrameName(options), summary.largest_shift_mm * 1e3);
  if (summary.invalid > 0) text += fmt::format("; {} invalid points (NaN or infinite) skipped", summary.invalid);
  if (!corrected.outside.empty()) text += fmt::format("; {} points outside the calibrated travel extrapolated", corrected.outside.size());
  text += fmt::format("\n  written to {}; standard uncertainties in {}\n", o.output, uncertainty_where);
  out.paths = {{"input", o.input}, {"output", o.output}};
  out.summary.json = doc;
  return out;
}

CorrectedFiles CorrectTileFiles(const CorrectOptions& o, const stage::Calibration& cal) {
  const imaging::TileLayout layout = imaging::ReadTileLayout(o.layout);
  const std::filesystem::path base = std::filesystem::path(o.layout).parent_path();
  std::vector<imaging::Surface> tiles;
  std::vector<imaging::PointCloud> clouds;
  std::vector<TileInput> inputs;
  for (const imaging::TileLayoutEntry& entry : layout.tiles) {
    if (!entry.stage_mm) {
      throw InputError(fmt::format("{}:{}: tile {} has no stage position; per-tile correction needs x,y (mm) of "
                                   "every tile", o.layout, entry.line, entry.file));
    }
    imaging::Surface tile = imaging::ReadSurface(base / entry.file, o.read);
    clouds.push_back(tile.height_map ? imaging::HeightMapToCloud(*tile.height_map) : *tile.cloud);
    inputs.push_back({entry.file, (base / entry.file).string(), *entry.stage_mm, nullptr});
    tiles.push_back(std::move(tile));
  }
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i].cloud = &clouds[i];
  const ScanCorrectionJob job = Job(o);
  const TileCorrection corrected = CorrectTiles(inputs, cal, job, o.layout);
  const std::vector<TileShift>& shifts = corrected.tiles;

  const std::filesystem::path out_dir(o.output);
  std::filesystem::create_directories(out_dir);
  std::string csv = fmt::format("# per-tile correction by fvm with {} (model {}), frame {}: each tile moved by "
                                "d (um), the model at its stage position; per_point_um: how far the per-point "
                                "correction departs from d at the tile's corners\n",
                                o.calibration, cal.model, FrameName(job.options));
  csv += "file,x,y,z,dx_um,dy_um,dz_um,u_x_um,u_y_um,u_z_um,per_point_um\n";
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const TileShift& t = shifts[i];
    imaging::Surface& tile = tiles[i];
    const std::filesystem::path target = out_dir / std::filesystem::path(t.file).filename();
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
  WriteFileAtomically(out_dir / "shifts.csv", csv);

  CorrectedFiles out;
  stage::ScanCorrectionOptions stage_frame = job.options;
  stage_frame.origin_mm.setZero();  // layout positions are stage positions
  nlohmann::json doc;  // sorted keys, as the command has always printed them
  doc = FrameJson(stage_frame, corrected.first_tile_mm);
  doc["tiles"] = nlohmann::json::array();
  for (const TileShift& t : shifts) {
    doc["tiles"].push_back({{"file", t.file},
                            {"shift_um", {t.shift.x() * 1e3, t.shift.y() * 1e3, t.shift.z() * 1e3}},
                            {"u_um", {t.u.x() * 1e3, t.u.y() * 1e3, t.u.z() * 1e3}},
                            {"per_point_um", t.per_point_mm * 1e3}});
  }
  doc["outside_travel"] = corrected.outside.size();
  doc["largest_per_point_um"] = corrected.largest_per_point_mm * 1e3;
  out.summary.text = fmt::format("corrected {} tiles of {} with model {} in the {} frame, each by one shift at its stage position; "
                                 "per-point correction would differ by up to {:.3f} um at the tiles' corners\n  written to {} "
                                 "(shifts.csv lists every tile)\n",
                                 shifts.size(), o.layout, cal.model, FrameName(job.options), corrected.largest_per_point_mm * 1e3,
                                 o.output);
  out.paths = {{"layout", o.layout}, {"output", o.output}};
  out.summary.json = doc;
  return out;
}

}  // namespace fvm::workflows
