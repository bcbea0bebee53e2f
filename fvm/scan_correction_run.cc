#include "core/statistics.h"
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

namespace fvm::cli {
namespace {

constexpr std::size_t kNamedPoints = 5;  // points a message names before "and N more"

std::string Point3(const Eigen::Vector3d& p) { return fmt::format("({:.4f}, {:.4f}, {:.4f})", p.x(), p.y(), p.z()); }

// "point 12" in file order, or "point (column 3, row 7)" on a grid: how a user finds it in the file.
std::string PointName(const imaging::PointCloud& cloud, std::size_t i) {
  if (!cloud.IsOrganised()) return fmt::format("point {}", i + 1);
  return fmt::format("point (column {}, row {})", i % static_cast<std::size_t>(cloud.width),
                     i / static_cast<std::size_t>(cloud.width));
}

std::string TravelText(const stage::ParameterLayout& layout) {
  const auto& t = layout.travel();
  return fmt::format("x {}..{}, y {}..{} mm", FormatShortest(t[0].min), FormatShortest(t[0].max),
                     FormatShortest(t[1].min), FormatShortest(t[1].max));
}

// Points whose stage coordinates lie outside the calibrated travel: refused, naming them, unless --extrapolate.
std::vector<std::size_t> CheckTravel(const ScanCorrectionArgs& args, const stage::Calibration& cal,
                                     const imaging::PointCloud& cloud, const std::string& name,
                                     const std::vector<std::string>& tile_names = {}) {
  const std::vector<std::size_t> outside = stage::PointsOutsideTravel(cal.layout, cloud.points, args.options.origin_mm);
  if (outside.empty() || args.extrapolate) return outside;
  std::string named;
  for (std::size_t k = 0; k < std::min(outside.size(), kNamedPoints); ++k) {
    const std::size_t i = outside[k];
    named += fmt::format("\n  {} at stage {} mm", tile_names.empty() ? PointName(cloud, i) : "tile " + tile_names[i],
                         Point3(cloud.points[i] + args.options.origin_mm));
  }
  if (outside.size() > kNamedPoints) named += fmt::format("\n  and {} more", outside.size() - kNamedPoints);
  const std::string fix = tile_names.empty()
                              ? "If the file's coordinates are not stage coordinates (an origin at the dataset's "
                                "corner), give the stage position of its origin with --origin X,Y,Z; to correct them "
                                "anyway, add --extrapolate"
                              : "The layout's x, y must be the tiles' stage positions (encoder readings); to correct "
                                "them anyway, add --extrapolate";
  throw InputError(fmt::format(
      "{}: {} of its {} lie outside the travel {} was identified on ({}), where the model only extrapolates:{}\n{}",
      name, outside.size(), tile_names.empty() ? "points" : "tiles", args.calibration, TravelText(cal.layout), named,
      fix));
}

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

nlohmann::json FrameJson(const ScanCorrectionArgs& args, const stage::ScanCorrector& corrector) {
  nlohmann::json doc = {{"frame", args.options.first_tile_frame ? "first-tile" : "stage"}};
  if (corrector.first_tile()) {
    const Eigen::Vector3d& a = corrector.first_tile()->frame().first_tile;
    doc["stitched_frame"] = stage::StitchedFrameName(*args.options.first_tile_frame);
    doc["first_tile_mm"] = {a.x(), a.y(), a.z()};
  }
  const Eigen::Vector3d& o = args.options.origin_mm;
  doc["origin_mm"] = {o.x(), o.y(), o.z()};
  return doc;
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
  const std::vector<std::size_t> outside = CheckTravel(args, cal, cloud, args.input);

  const stage::ScanCorrector corrector(cal, args.options, cloud.points);
  std::vector<Eigen::Vector3d> u;
  const stage::ScanCorrectionSummary summary =
      stage::CorrectScanInPlace(corrector, cloud.points, map_out ? nullptr : &u, args.threads);
  if (summary.corrected == 0) throw InputError(args.input + ": no valid point to correct (every point is NaN or infinite)");

  std::string uncertainty_where;
  if (!map_out && args.resample_mm > 0.0) {
    cloud = imaging::HeightMapToCloud(imaging::ResampleOnGrid(cloud, args.resample_mm, args.input));
    u.clear();
    for (const Eigen::Vector3d& p : cloud.points) {
      u.push_back(p.allFinite() ? Eigen::Vector3d(corrector.Correct(p).covariance.diagonal().cwiseMax(0.0).cwiseSqrt())
                                : Eigen::Vector3d::Constant(NAN));
    }
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
    nlohmann::json doc = FrameJson(args, corrector);
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

// The median height of a tile's valid points: where the tile's rigid shift is evaluated along z.
double MedianZ(const imaging::PointCloud& cloud) {
  std::vector<double> z;
  for (const Eigen::Vector3d& p : cloud.points) {
    if (p.allFinite()) z.push_back(p.z());
  }
  return HighMedian(std::move(z));
}

// One tile of a stitching-free scan: the whole tile moved by the stage model at its stage position.
struct TileShift {
  std::string file;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // stage, mm
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  double per_point_mm = 0.0;  // largest difference of the per-point correction from the shift over the tile
};

void RunLayout(const ScanCorrectionArgs& args, const stage::Calibration& cal) {
  const imaging::TileLayout layout = imaging::ReadTileLayout(args.layout);
  const std::filesystem::path base = std::filesystem::path(args.layout).parent_path();
  std::vector<imaging::Surface> tiles;
  std::vector<TileShift> shifts;
  for (const imaging::TileLayoutEntry& entry : layout.tiles) {
    if (!entry.stage_mm) {
      throw InputError(fmt::format("{}:{}: tile {} has no stage position; per-tile correction needs x,y (mm) of "
                                   "every tile", args.layout, entry.line, entry.file));
    }
    imaging::Surface tile = imaging::ReadSurface(base / entry.file, args.read);
    const imaging::PointCloud cloud = tile.height_map ? imaging::HeightMapToCloud(*tile.height_map) : *tile.cloud;
    const imaging::PointCloudStats stats = imaging::ComputeStats(cloud);
    if (stats.valid_points == 0) throw InputError((base / entry.file).string() + ": no valid point in the tile");
    TileShift t;
    t.file = entry.file;
    t.centre = Eigen::Vector3d(entry.stage_mm->x(), entry.stage_mm->y(), MedianZ(cloud) + args.options.origin_mm.z());
    // The tile's footprint about its centre, to say how far one shift is from correcting every point.
    t.per_point_mm = 0.5 * (stats.max - stats.min).head<2>().norm();
    shifts.push_back(t);
    tiles.push_back(std::move(tile));
  }
  std::vector<Eigen::Vector3d> centres;
  for (const TileShift& t : shifts) centres.push_back(t.centre);
  const imaging::PointCloud centre_cloud = imaging::MakeUnorganisedCloud(centres);
  ScanCorrectionArgs stage_args = args;
  stage_args.options.origin_mm.setZero();  // layout positions are stage positions
  std::vector<std::string> tile_names;
  for (const TileShift& t : shifts) tile_names.push_back(t.file);
  const std::vector<std::size_t> outside = CheckTravel(stage_args, cal, centre_cloud, args.layout, tile_names);
  const stage::ScanCorrector corrector(cal, stage_args.options, centres);
  double largest_per_point = 0.0;
  for (TileShift& t : shifts) {
    const stage::CorrectedPoint c = corrector.Correct(t.centre);
    t.shift = c.position - t.centre;
    t.u = c.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    const double half = t.per_point_mm / std::sqrt(2.0);
    t.per_point_mm = 0.0;
    for (const Eigen::Vector3d corner : {Eigen::Vector3d(-half, -half, 0), Eigen::Vector3d(half, -half, 0),
                                         Eigen::Vector3d(-half, half, 0), Eigen::Vector3d(half, half, 0)}) {
      t.per_point_mm = std::max(t.per_point_mm, (corrector.Shift(t.centre + corner) - t.shift).norm());
    }
    largest_per_point = std::max(largest_per_point, t.per_point_mm);
  }

  const std::filesystem::path out(args.output);
  std::filesystem::create_directories(out);
  std::string csv = fmt::format("# per-tile correction by fvm with {} (model {}), frame {}: each tile moved by "
                                "d (um), the model at its stage position; per_point_um: how far the per-point "
                                "correction departs from d at the tile's corners\n",
                                args.calibration, cal.model, FrameName(args));
  csv += "file,x,y,z,dx_um,dy_um,dz_um,u_x_um,u_y_um,u_z_um,per_point_um\n";
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const TileShift& t = shifts[i];
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
    nlohmann::json doc = FrameJson(stage_args, corrector);
    doc["layout"] = args.layout;
    doc["output"] = args.output;
    doc["tiles"] = nlohmann::json::array();
    for (const TileShift& t : shifts) {
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
