#include "fvm/fit_shape.h"

#include <fmt/core.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/exit_codes.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/surface_file.h"
#include "imaging/point_cloud.h"
#include "imaging/shape_fit.h"

namespace fvm::cli {
namespace {

// The points of the file: an unorganised cloud's as they are (a NaN there is bad input, which the fit names);
// a height map's or an organised cloud's valid points (NaN marks a missing grid point there).
std::vector<Eigen::Vector3d> ReadPoints(const ShapeFitArgs& args) {
  imaging::Surface surface = imaging::ReadSurface(args.file, args.read.ToOptions());
  imaging::PointCloud cloud =
      surface.height_map ? imaging::HeightMapToCloud(*surface.height_map) : std::move(*surface.cloud);
  if (!cloud.IsOrganised()) return std::move(cloud.points);
  std::vector<Eigen::Vector3d> valid;
  for (const auto& p : cloud.points) {
    if (p.allFinite()) valid.push_back(p);
  }
  return valid;
}

nlohmann::ordered_json Uncertainty(bool known, double value_um) {
  return known ? nlohmann::ordered_json(RoundTo(value_um, 1e4)) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json Json(const ShapeFitArgs& args, const imaging::ShapeFit& fit) {
  nlohmann::ordered_json doc;  // the contract's keys first, in its order; coordinates with every digit
  doc["shape"] = imaging::ShapeName(fit.shape);
  doc["points"] = fit.points;
  const bool u = fit.has_uncertainty;
  if (fit.shape == imaging::Shape::kSphere) {
    doc["centre_mm"] = {fit.centre_mm.x(), fit.centre_mm.y(), fit.centre_mm.z()};
    doc["radius_mm"] = fit.radius_mm;
    doc["u_centre_um"] = {Uncertainty(u, fit.u_centre_mm.x() * 1e3), Uncertainty(u, fit.u_centre_mm.y() * 1e3),
                          Uncertainty(u, fit.u_centre_mm.z() * 1e3)};
    doc["u_radius_um"] = Uncertainty(u, fit.u_radius_mm * 1e3);
  } else {
    doc["point_mm"] = {fit.point_mm.x(), fit.point_mm.y(), fit.point_mm.z()};
    doc["normal"] = {fit.normal.x(), fit.normal.y(), fit.normal.z()};
    doc["u_normal_urad"] = Uncertainty(u, fit.u_normal_rad * 1e6);
  }
  doc["rms_um"] = RoundTo(fit.rms_mm * 1e3, 1e6);
  doc["outliers"] = fit.outliers;
  doc["file"] = args.file;
  doc["robust"] = args.robust;
  doc["method"] = fit.method;
  return doc;
}

void PrintShapeText(const ShapeFitArgs& args, const imaging::ShapeFit& fit) {
  fmt::print("{}: {} fitted to {} of {} points\n  {}\n", args.file, imaging::ShapeName(fit.shape),
             fit.points - fit.outliers, fit.points, fit.method);
  const auto u = [&](double mm) { return fit.has_uncertainty ? fmt::format("{:.4f}", mm * 1e3) : std::string("-"); };
  if (fit.shape == imaging::Shape::kSphere) {
    fmt::print("  centre     {:.9f} {:.9f} {:.9f} mm  (u {} {} {} um)\n", fit.centre_mm.x(), fit.centre_mm.y(),
               fit.centre_mm.z(), u(fit.u_centre_mm.x()), u(fit.u_centre_mm.y()), u(fit.u_centre_mm.z()));
    fmt::print("  radius     {:.9f} mm  (u {} um), diameter {:.9f} mm\n", fit.radius_mm, u(fit.u_radius_mm),
               2 * fit.radius_mm);
  } else {
    fmt::print("  centroid   {:.9f} {:.9f} {:.9f} mm\n", fit.point_mm.x(), fit.point_mm.y(), fit.point_mm.z());
    fmt::print("  normal     {:.12f} {:.12f} {:.12f}  (u {} urad)\n", fit.normal.x(), fit.normal.y(), fit.normal.z(),
               fit.has_uncertainty ? fmt::format("{:.4f}", fit.u_normal_rad * 1e6) : std::string("-"));
  }
  fmt::print("  rms        {:.4f} um (orthogonal distances of the points used)\n", fit.rms_mm * 1e3);
  fmt::print("  outliers   {}\n", fit.outliers);
  if (!fit.has_uncertainty) fmt::print("  the points only just determine the {}: no uncertainty\n", imaging::ShapeName(fit.shape));
}

}  // namespace

void RunShapeFit(const ShapeFitArgs& args) {
  imaging::ShapeFitOptions options;
  options.shape = args.shape == "plane" ? imaging::Shape::kPlane : imaging::Shape::kSphere;
  options.robust = args.robust;
  imaging::ShapeFit fit;
  try {
    const std::vector<Eigen::Vector3d> points = ReadPoints(args);
    fit = imaging::FitShape(points, options);
  } catch (const InputError& e) {
    const std::string what = e.what();
    throw InputError(what.rfind(args.file, 0) == 0 ? what : args.file + ": " + what);
  } catch (const NotConvergedError& e) {
    throw NotConvergedError(args.file + ": " + e.what());
  }
  if (args.json) {
    fmt::print("{}\n", Json(args, fit).dump(2));
  } else {
    PrintShapeText(args, fit);
  }
}

}  // namespace fvm::cli
