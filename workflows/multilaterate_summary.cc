#include "workflows/multilaterate_summary.h"

#include <fmt/core.h>

namespace fvm::workflows {
namespace {

std::string FrameOf(const MultilaterateOptions& o) {
  return o.self_calibrate ? "station 1 at the origin, station 2 on +x, station 3 in the xy plane (+y)" : "the stations file's";
}

std::string UncertaintyOf(const MultilaterateOptions& o) {
  return o.self_calibrate || o.angles ? "bundle covariance (a priori), stations' uncertainty included"
                                      : "each point's own solve (a priori)";
}

nlohmann::json PointsJson(const Multilateration& m) {
  nlohmann::json points = nlohmann::json::array();
  for (const artefacts::MultilateratedPoint& p : m.Points()) {
    points.push_back({{"id", p.id}, {"x", p.position.x()}, {"y", p.position.y()}, {"z", p.position.z()},
                      {"u_x", p.u.x()}, {"u_y", p.u.y()}, {"u_z", p.u.z()}});
  }
  return points;
}

nlohmann::json StationsJson(const Multilateration& m, const MultilaterateOptions& o) {
  const stage::MultilaterationResult& result = m.result;
  nlohmann::json stations = nlohmann::json::array();
  for (size_t i = 0; i < result.stations.size(); ++i) {
    nlohmann::json s{{"name", m.problem.station_names[i]}, {"x", result.stations[i].x()},
                     {"y", result.stations[i].y()},        {"z", result.stations[i].z()},
                     {"u_x", result.station_u[i].x()},     {"u_y", result.station_u[i].y()},
                     {"u_z", result.station_u[i].z()}};
    if (o.angles) {
      const Eigen::Vector3d& r = result.station_rotation[i];
      s["rotation_vector_rad"] = {r.x(), r.y(), r.z()};
    }
    stations.push_back(s);
  }
  return stations;
}

nlohmann::json MultilaterationJson(const Multilateration& m, const MultilaterateOptions& o,
                    const std::optional<stage::ResidualSummary>& truth_error) {
  const stage::MultilaterationResult& result = m.result;
  const stage::NetworkGeometry& g = result.geometry;
  nlohmann::json doc;
  doc["mode"] = o.angles ? "bundle" : "ranges";
  doc["stations_known"] = !o.self_calibrate;
  doc["frame"] = FrameOf(o);
  doc["weights"] = "tracker " + m.options.noise.name;
  doc["uncertainty"] = UncertaintyOf(o);
  doc["points"] = PointsJson(m);
  doc["stations"] = StationsJson(m, o);
  doc["range_rms_um"] = result.range_rms_mm * 1e3;
  doc["weighted_rms"] = result.weighted_rms;
  doc["range_rms_sigmas"] = result.range_rms_sigmas;
  doc["u_mean_um"] = m.u_mean_mm * 1e3;
  doc["u_max_um"] = m.u_max_mm * 1e3;
  doc["geometry"] = {{"angle_min_deg", g.min_angle_deg}, {"angle_mean_deg", g.mean_angle_deg},
                     {"angle_max_deg", g.max_angle_deg}, {"pdop_mean", g.mean_pdop}, {"pdop_max", g.max_pdop}};
  doc["unobservable"] = result.unobservable;
  doc["iterations"] = result.iterations;
  doc["converged"] = result.converged;
  if (truth_error) {
    doc["truth_error"] = {{"mean_um", truth_error->mean_mm * 1e3}, {"rms_um", truth_error->rms_mm * 1e3},
                          {"max_um", truth_error->max_mm * 1e3}};
  }
  return doc;
}

std::string Text(const Multilateration& m, const MultilaterateOptions& o,
                 const std::optional<stage::ResidualSummary>& truth_error, const std::string& truth_file,
                 const std::string& written) {
  const stage::MultilaterationResult& result = m.result;
  const stage::NetworkGeometry& g = result.geometry;
  std::string text = fmt::format(
      "multilaterated {} points from {} stations ({}, {} stations, tracker {} weights): range rms {:.2f} um "
      "({:.2f} sigmas of the noise model), weighted rms {:.2f}\n",
      result.points.size(), result.stations.size(), m.Mode(), o.self_calibrate ? "self-calibrated" : "known",
      m.options.noise.name, result.range_rms_mm * 1e3, result.range_rms_sigmas, result.weighted_rms);
  text += fmt::format("  geometry: angles between lines of sight {:.1f} / {:.1f} / {:.1f} deg (min / mean / max, folded to "
                      "0-90: 90 is ideal), PDOP mean {:.2f} (max {:.2f})\n",
                      g.min_angle_deg, g.mean_angle_deg, g.max_angle_deg, g.mean_pdop, g.max_pdop);
  text += fmt::format("  point uncertainty (3D, 1 sigma): mean {:.1f} um, max {:.1f} um\n", m.u_mean_mm * 1e3, m.u_max_mm * 1e3);
  for (size_t i = 0; i < result.stations.size(); ++i) {
    const Eigen::Vector3d& s = result.stations[i];
    const Eigen::Vector3d& u = result.station_u[i];
    text += fmt::format("  station {}: {:.4f}, {:.4f}, {:.4f} mm{}\n", m.problem.station_names[i], s.x(), s.y(), s.z(),
                        u.norm() > 0 ? fmt::format(" (u {:.1f}, {:.1f}, {:.1f} um)", u.x() * 1e3, u.y() * 1e3, u.z() * 1e3)
                                     : std::string(o.self_calibrate ? " (held)" : ""));
  }
  if (truth_error) {
    text += fmt::format("  error against {}: mean {:.1f} um, max {:.1f} um\n", truth_file, truth_error->mean_mm * 1e3,
                        truth_error->max_mm * 1e3);
  }
  for (const std::string& u : result.unobservable) text += fmt::format("  unobservable, held at its start: {}\n", u);
  if (!written.empty()) text += fmt::format("  written {}\n", written);
  return text;
}

}  // namespace

Summary Summarize(const Multilateration& m, const MultilaterateOptions& options,
                  const std::optional<stage::ResidualSummary>& truth_error, const std::string& truth_file,
                  const std::string& written) {
  return {MultilaterationJson(m, options, truth_error), Text(m, options, truth_error, truth_file, written), std::nullopt};
}

std::vector<std::string> PointsFileComments(const Multilateration& m, const MultilaterateOptions& o) {
  return {"fvm multilaterate: points from " + o.readings + " (" + m.Mode() + ", " +
              (o.self_calibrate ? "self-calibrated stations" : "known stations") + ", tracker " + m.options.noise.name +
              " weights)",
          "frame: " + FrameOf(o) + "; x,y,z and standard uncertainties u_x,u_y,u_z in mm (" + UncertaintyOf(o) + ")"};
}

}  // namespace fvm::workflows
