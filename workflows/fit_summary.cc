// Summarize(FitResult) of workflows/fit.h: the --json document and the text of `fvm fit`, for the calotte search
// and for one shape.

#include <fmt/core.h>

#include <cmath>

#include "core/number_text.h"
#include "workflows/fit.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

Json CalotteJson(const imaging::DetectedCalotte& c) {
  const Eigen::Vector3d sd = c.fit.centre_covariance_mm2.diagonal().cwiseSqrt();
  return {{"id", c.id},
          {"x", RoundTo(c.fit.centre_mm.x(), 1e7)},
          {"y", RoundTo(c.fit.centre_mm.y(), 1e7)},
          {"z", RoundTo(c.fit.centre_mm.z(), 1e7)},
          {"radius", RoundTo(c.fit.radius_mm, 1e7)},
          {"form_rms_um", RoundTo(c.fit.rms_deviation_mm * 1e3, 1e4)},
          {"points", c.fit.inliers},
          {"u_um", {RoundTo(sd.x() * 1e3, 1e4), RoundTo(sd.y() * 1e3, 1e4), RoundTo(sd.z() * 1e3, 1e4)}},
          {"min_dev_um", RoundTo(c.fit.min_deviation_mm * 1e3, 1e4)},
          {"max_dev_um", RoundTo(c.fit.max_deviation_mm * 1e3, 1e4)},
          {"mean_dev_um", RoundTo(c.fit.mean_deviation_mm * 1e3, 1e4)},
          {"outliers", c.fit.points - c.fit.inliers},
          {"converged", c.fit.converged},
          {"fit_stop", c.fit.stop_reason},
          {"at_border", c.at_border}};
}

Json CalottesJson(const FoundCalottes& found) {
  const imaging::CalotteDetection& detection = found.detection;
  Json doc;
  doc["calottes"] = Json::array();
  for (const auto& c : detection.calottes) doc["calottes"].push_back(CalotteJson(c));
  doc["method"] = found.method;
  doc["artefact"] = found.artefact ? Json(found.artefact->name) : Json(nullptr);
  doc["face"] = {{"slope_x", detection.face.b},
                 {"slope_y", detection.face.c},
                 {"sigma_um", RoundTo(detection.face.sigma_mm * 1e3, 1e4)}};
  if (found.layout) {
    doc["layout"] = {{"rotation_deg", RoundTo(found.layout->rotation_rad * 180 / M_PI, 1e6)},
                     {"scale", RoundTo(found.layout->scale, 1e9)},
                     {"rms_um", RoundTo(found.layout->rms_mm * 1e3, 1e4)}};
  }
  doc["rejected"] = Json::array();
  for (const auto& r : detection.rejected) {
    doc["rejected"].push_back(
        {{"x", RoundTo(r.centre_mm.x(), 1e4)}, {"y", RoundTo(r.centre_mm.y(), 1e4)}, {"reason", r.reason}});
  }
  return doc;
}

std::string CalottesHeader(const std::string& file, const FoundCalottes& found) {
  const imaging::CalotteDetection& d = found.detection;
  std::string t;
  if (found.map) {
    t = fmt::format("{}: {} x {} points of {:.3g} x {:.3g} um; face noise {:.3f} um, tilt ({:.3g}, {:.3g}) mrad\n",
                    file, found.map->size_x, found.map->size_y, found.map->dx_mm * 1e3, found.map->dy_mm * 1e3,
                    d.face.sigma_mm * 1e3, d.face.b * 1e3, d.face.c * 1e3);
  } else {
    t = fmt::format("{}: unorganised cloud, calottes found by {}; face noise {:.3f} um, tilt ({:.3g}, {:.3g}) mrad\n",
                    file, found.method, d.face.sigma_mm * 1e3, d.face.b * 1e3, d.face.c * 1e3);
  }
  if (found.layout) {
    t += fmt::format("{} layout: turned {:.3f} deg, scale {:.6f}, {:.2f} um rms from nominal\n", found.artefact->name,
                     found.layout->rotation_rad * 180 / M_PI, found.layout->scale, found.layout->rms_mm * 1e3);
  }
  return t;
}

std::string CalottesText(const std::string& file, const FoundCalottes& found) {
  const imaging::CalotteDetection& detection = found.detection;
  std::string t = CalottesHeader(file, found);
  t += fmt::format("\n{:>4}  {:>12}  {:>12}  {:>12}  {:>10}  {:>8}  {:>20}  {:>8}\n", "id", "x [mm]", "y [mm]",
                   "z [mm]", "r [mm]", "form [um]", "u(x, y, z) [um]", "points");
  for (const auto& c : detection.calottes) {
    const Eigen::Vector3d sd = c.fit.centre_covariance_mm2.diagonal().cwiseSqrt() * 1e3;
    t += fmt::format("{:>4}  {:>12.6f}  {:>12.6f}  {:>12.6f}  {:>10.6f}  {:>9.3f}  {:>6.3f} {:>6.3f} {:>6.3f}  {:>8}{}\n",
                     c.id, c.fit.centre_mm.x(), c.fit.centre_mm.y(), c.fit.centre_mm.z(), c.fit.radius_mm,
                     c.fit.rms_deviation_mm * 1e3, sd.x(), sd.y(), sd.z(), c.fit.inliers,
                     c.at_border ? "  cut by the map's border" : "");
    if (!c.fit.converged) t += fmt::format("      calotte {}: the sphere fit did NOT converge ({})\n", c.id, c.fit.stop_reason);
  }
  for (const auto& r : detection.rejected) {
    t += fmt::format("not a calotte at ({:.3f}, {:.3f}) mm: {}\n", r.centre_mm.x(), r.centre_mm.y(), r.reason);
  }
  if (found.artefact && detection.calottes.size() < found.artefact->calottes.size()) {
    std::string missing;
    for (const auto& n : found.artefact->calottes) {
      bool seen = false;
      for (const auto& c : detection.calottes) seen = seen || c.id == n.id;
      if (!seen) missing += (missing.empty() ? "" : ", ") + std::to_string(n.id);
    }
    t += fmt::format("not in this map: calotte {}\n", missing);
  }
  return t;
}

Json UncertaintyOrNull(bool known, double value_um) { return known ? Json(RoundTo(value_um, 1e4)) : Json(nullptr); }

Json ShapeJson(const imaging::ShapeFit& fit, bool robust) {
  Json doc;  // the contract's keys first, in its order; coordinates with every digit
  doc["shape"] = imaging::ShapeName(fit.shape);
  doc["points"] = fit.points;
  const bool u = fit.has_uncertainty;
  if (fit.shape == imaging::Shape::kSphere) {
    doc["centre_mm"] = {fit.centre_mm.x(), fit.centre_mm.y(), fit.centre_mm.z()};
    doc["radius_mm"] = fit.radius_mm;
    doc["u_centre_um"] = {UncertaintyOrNull(u, fit.u_centre_mm.x() * 1e3), UncertaintyOrNull(u, fit.u_centre_mm.y() * 1e3),
                          UncertaintyOrNull(u, fit.u_centre_mm.z() * 1e3)};
    doc["u_radius_um"] = UncertaintyOrNull(u, fit.u_radius_mm * 1e3);
  } else {
    doc["point_mm"] = {fit.point_mm.x(), fit.point_mm.y(), fit.point_mm.z()};
    doc["normal"] = {fit.normal.x(), fit.normal.y(), fit.normal.z()};
    doc["u_normal_urad"] = UncertaintyOrNull(u, fit.u_normal_rad * 1e6);
  }
  doc["rms_um"] = RoundTo(fit.rms_mm * 1e3, 1e6);
  doc["outliers"] = fit.outliers;
  doc["robust"] = robust;
  doc["method"] = fit.method;
  return doc;
}

std::string ShapeText(const std::string& file, const imaging::ShapeFit& fit) {
  std::string t = fmt::format("{}: {} fitted to {} of {} points\n  {}\n", file, imaging::ShapeName(fit.shape),
                              fit.points - fit.outliers, fit.points, fit.method);
  const auto u = [&](double mm) { return fit.has_uncertainty ? fmt::format("{:.4f}", mm * 1e3) : std::string("-"); };
  if (fit.shape == imaging::Shape::kSphere) {
    t += fmt::format("  centre     {:.9f} {:.9f} {:.9f} mm  (u {} {} {} um)\n", fit.centre_mm.x(), fit.centre_mm.y(),
                     fit.centre_mm.z(), u(fit.u_centre_mm.x()), u(fit.u_centre_mm.y()), u(fit.u_centre_mm.z()));
    t += fmt::format("  radius     {:.9f} mm  (u {} um), diameter {:.9f} mm\n", fit.radius_mm, u(fit.u_radius_mm),
                     2 * fit.radius_mm);
  } else {
    t += fmt::format("  centroid   {:.9f} {:.9f} {:.9f} mm\n", fit.point_mm.x(), fit.point_mm.y(), fit.point_mm.z());
    t += fmt::format("  normal     {:.12f} {:.12f} {:.12f}  (u {} urad)\n", fit.normal.x(), fit.normal.y(),
                     fit.normal.z(), fit.has_uncertainty ? fmt::format("{:.4f}", fit.u_normal_rad * 1e6) : std::string("-"));
  }
  t += fmt::format("  rms        {:.4f} um (orthogonal distances of the points used)\n", fit.rms_mm * 1e3);
  t += fmt::format("  outliers   {}\n", fit.outliers);
  if (!fit.has_uncertainty) t += fmt::format("  the points only just determine the {}: no uncertainty\n", imaging::ShapeName(fit.shape));
  return t;
}

}  // namespace

Summary Summarize(const FitResult& result) {
  Summary s;
  if (result.shape) {
    s.json = ShapeJson(*result.shape, result.options.robust);
    s.text = ShapeText(result.file, *result.shape);
  } else {
    s.json = CalottesJson(*result.found);
    s.text = CalottesText(result.file, *result.found);
  }
  return s;
}

}  // namespace fvm::workflows
