// fvm multilaterate READINGS.csv --stations S.json -o POINTS.csv [--self-calibrate] [--angles]: points from the
// ranges (and angles) of several tracker stations, with the stations known or calibrated with the points.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/tracker_readings.h"
#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "fvm/commands.h"
#include "stage/multilateration.h"
#include "stage/tracker.h"

namespace fvm::cli {
namespace {

struct MultilaterateArgs {
  std::string readings;
  std::string stations;
  bool self_calibrate = false;
  bool angles = false;
  std::string tracker = "published";
  std::string output;
  std::string nominal;
  std::string verify_readings;
  std::string truth;
  bool json = false;
};

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

void Run(const MultilaterateArgs& args) {
  const artefacts::MultilaterationReadings data = artefacts::ReadMultilaterationReadings(args.readings);
  std::optional<std::vector<artefacts::Station>> stations;
  if (!args.stations.empty()) stations = artefacts::ReadStations(args.stations);
  if (!stations && !(args.self_calibrate && data.angles)) {
    throw InputError(fmt::format("{}: no stations: give --stations S.json (known positions, or starting values with "
                                 "--self-calibrate); a self-calibration without them starts from the angles, which "
                                 "this file does not have",
                                 args.readings));
  }
  if (args.angles && !data.angles) {
    throw InputError(fmt::format("{}: --angles needs azimuth,elevation columns (rad) beside id,station,range", args.readings));
  }

  // The problem: points in file order, stations in the stations file's order (or of first appearance).
  stage::MultilaterationProblem problem;
  std::map<std::string, int, std::less<>> point_index, station_index;
  if (stations) {
    for (const artefacts::Station& s : *stations) {
      station_index.emplace(s.name, static_cast<int>(problem.station_names.size()));
      problem.station_names.push_back(s.name);
      problem.stations.push_back(s.position);
    }
  }
  std::vector<int> readings_per_station(problem.station_names.size(), 0);
  for (const artefacts::StationReadingRow& r : data.rows) {
    auto s = station_index.find(r.station);
    if (s == station_index.end()) {
      if (stations) {
        throw InputError(fmt::format("{}:{}: point {}: station {} is not in {} (stations: {})", data.source, r.line, r.id,
                                     r.station, args.stations, Join(problem.station_names)));
      }
      s = station_index.emplace(r.station, static_cast<int>(problem.station_names.size())).first;
      problem.station_names.push_back(r.station);
      readings_per_station.push_back(0);
    }
    auto p = point_index.find(r.id);
    if (p == point_index.end()) {
      p = point_index.emplace(r.id, static_cast<int>(problem.point_ids.size())).first;
      problem.point_ids.push_back(r.id);
    }
    ++readings_per_station[static_cast<size_t>(s->second)];
    stage::StationReading m;
    m.point = p->second;
    m.station = s->second;
    m.range_mm = r.range_mm;
    m.has_angles = data.angles;
    m.azimuth_rad = r.azimuth_rad;
    m.elevation_rad = r.elevation_rad;
    problem.readings.push_back(m);
  }
  for (size_t i = 0; i < readings_per_station.size(); ++i) {
    if (readings_per_station[i] == 0) {
      throw InputError(fmt::format("{}: station {} has no readings in {}; remove it or add its readings", args.stations,
                                   problem.station_names[i], args.readings));
    }
  }

  stage::MultilaterationOptions options;
  options.noise = stage::TrackerNoise::Preset(args.tracker);
  options.self_calibrate = args.self_calibrate;
  options.use_angles = args.angles;
  const std::string mode = args.angles ? "bundle adjustment: ranges and angles" : "ranges only";
  stage::MultilaterationResult result;
  try {
    if (args.self_calibrate && problem.station_names.size() < 4) {
      const std::vector<std::string> lost = stage::UnobservableStationParameters(problem, options);
      std::string list;
      for (const std::string& u : lost) list += "\n  " + u;
      throw InputError(fmt::format("{}: self-calibration needs every point seen by at least 4 stations; with {} stations "
                                   "{} direction(s) of the stations stay unobservable whatever the number of points:{}\n"
                                   "add a station, or give the stations' positions and leave out --self-calibrate",
                                   args.readings, problem.station_names.size(), lost.size(), list));
    }
    result = stage::Multilaterate(problem, options);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}", args.readings, e.what()));
  }

  // Nominal coordinates for fvm verify: from the readings' x,y,z or --nominal.
  std::map<std::string, artefacts::NominalPoint, std::less<>> nominal;
  if (!args.nominal.empty()) {
    nominal = artefacts::ReadNominalPoints(args.nominal);
  } else if (data.nominal) {
    for (const artefacts::StationReadingRow& r : data.rows) nominal.emplace(r.id, artefacts::NominalPoint{r.nominal, ""});
  }
  std::optional<artefacts::TrackerReadings> for_verify;
  if (!args.verify_readings.empty()) {
    if (nominal.empty()) {
      throw InputError(fmt::format("--verify-readings {}: needs each point's nominal machine coordinates: x,y,z columns in "
                                   "{} or --nominal POINTS.csv (id,x,y,z)",
                                   args.verify_readings, args.readings));
    }
    for_verify.emplace();
    for_verify->comments = {"fvm multilaterate: multilaterated points as tracker readings for fvm verify",
                            fmt::format("from {} ({}, {} stations{}); xt,yt,zt in the stations' frame (mm)", args.readings,
                                        mode, problem.station_names.size(), args.self_calibrate ? ", self-calibrated" : "")};
    for (size_t j = 0; j < problem.point_ids.size(); ++j) {
      const auto it = nominal.find(problem.point_ids[j]);
      if (it == nominal.end()) {
        throw InputError(fmt::format("{}: point {} has no nominal coordinates there", args.nominal.empty() ? args.readings : args.nominal,
                                     problem.point_ids[j]));
      }
      artefacts::TrackerReading t;
      t.id = problem.point_ids[j];
      t.nominal = it->second.position;
      t.measured = result.points[j];
      t.approach = it->second.approach;
      for_verify->points.push_back(std::move(t));
    }
  }

  // Summaries.
  std::vector<artefacts::MultilateratedPoint> points;
  double u_sum = 0, u_max = 0;
  nlohmann::json jpoints = nlohmann::json::array();
  for (size_t j = 0; j < result.points.size(); ++j) {
    const Eigen::Vector3d u = result.point_covariance[j].diagonal().cwiseMax(0.0).cwiseSqrt();
    points.push_back({problem.point_ids[j], result.points[j], u});
    u_sum += u.norm();
    u_max = std::max(u_max, u.norm());
    jpoints.push_back({{"id", problem.point_ids[j]}, {"x", result.points[j].x()}, {"y", result.points[j].y()},
                       {"z", result.points[j].z()}, {"u_x", u.x()}, {"u_y", u.y()}, {"u_z", u.z()}});
  }
  const double u_mean = u_sum / static_cast<double>(result.points.size());
  nlohmann::json jstations = nlohmann::json::array();
  for (size_t i = 0; i < result.stations.size(); ++i) {
    nlohmann::json s{{"name", problem.station_names[i]},
                     {"x", result.stations[i].x()},
                     {"y", result.stations[i].y()},
                     {"z", result.stations[i].z()},
                     {"u_x", result.station_u[i].x()},
                     {"u_y", result.station_u[i].y()},
                     {"u_z", result.station_u[i].z()}};
    if (args.angles) {
      const Eigen::Vector3d& r = result.station_rotation[i];
      s["rotation_vector_rad"] = {r.x(), r.y(), r.z()};
    }
    jstations.push_back(s);
  }
  const stage::NetworkGeometry& g = result.geometry;
  nlohmann::json doc;
  doc["readings"] = args.readings;
  doc["mode"] = args.angles ? "bundle" : "ranges";
  doc["stations_known"] = !args.self_calibrate;
  doc["frame"] = args.self_calibrate ? "station 1 at the origin, station 2 on +x, station 3 in the xy plane (+y)"
                                     : "the stations file's";
  doc["weights"] = "tracker " + options.noise.name;
  doc["uncertainty"] = args.self_calibrate || args.angles ? "bundle covariance (a priori), stations' uncertainty included"
                                                          : "each point's own solve (a priori)";
  doc["points"] = jpoints;
  doc["stations"] = jstations;
  doc["range_rms_um"] = result.range_rms_mm * 1e3;
  doc["weighted_rms"] = result.weighted_rms;
  doc["range_rms_sigmas"] = result.range_rms_sigmas;
  doc["u_mean_um"] = u_mean * 1e3;
  doc["u_max_um"] = u_max * 1e3;
  doc["geometry"] = {{"angle_min_deg", g.min_angle_deg}, {"angle_mean_deg", g.mean_angle_deg},
                     {"angle_max_deg", g.max_angle_deg}, {"pdop_mean", g.mean_pdop}, {"pdop_max", g.max_pdop}};
  doc["unobservable"] = result.unobservable;
  doc["iterations"] = result.iterations;
  doc["converged"] = result.converged;

  // --truth: the error of each point against known true positions (simulations: true_points.csv).
  std::optional<std::pair<double, double>> truth_error;  // mean, max (mm)
  if (!args.truth.empty()) {
    const auto truth = artefacts::ReadNominalPoints(args.truth);
    double sum = 0, worst = 0, sum2 = 0;
    for (size_t j = 0; j < result.points.size(); ++j) {
      const auto it = truth.find(problem.point_ids[j]);
      if (it == truth.end()) throw InputError(fmt::format("{}: point {} is not there", args.truth, problem.point_ids[j]));
      const double e = (result.points[j] - it->second.position).norm();
      sum += e;
      sum2 += e * e;
      worst = std::max(worst, e);
    }
    const double n = static_cast<double>(result.points.size());
    truth_error = std::make_pair(sum / n, worst);
    doc["truth_error"] = {{"mean_um", sum / n * 1e3}, {"rms_um", std::sqrt(sum2 / n) * 1e3}, {"max_um", worst * 1e3}};
  }

  // Outputs only after every check.
  if (!args.output.empty()) {
    artefacts::WriteMultilateratedPoints(
        args.output, points,
        {"fvm multilaterate: points from " + args.readings + " (" + mode + ", " +
             (args.self_calibrate ? "self-calibrated stations" : "known stations") + ", tracker " + options.noise.name +
             " weights)",
         std::string("frame: ") + doc["frame"].get<std::string>() + "; x,y,z and standard uncertainties u_x,u_y,u_z in mm (" +
             doc["uncertainty"].get<std::string>() + ")"});
  }
  if (for_verify) artefacts::WriteTrackerReadings(args.verify_readings, *for_verify);

  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("multilaterated {} points from {} stations ({}, {} stations, tracker {} weights): range rms {:.2f} um "
               "({:.2f} sigmas of the noise model), weighted rms {:.2f}\n",
               result.points.size(), result.stations.size(), mode, args.self_calibrate ? "self-calibrated" : "known",
               options.noise.name, result.range_rms_mm * 1e3, result.range_rms_sigmas, result.weighted_rms);
    fmt::print("  geometry: angles between lines of sight {:.1f} / {:.1f} / {:.1f} deg (min / mean / max, folded to "
               "0-90: 90 is ideal), PDOP mean {:.2f} (max {:.2f})\n",
               g.min_angle_deg, g.mean_angle_deg, g.max_angle_deg, g.mean_pdop, g.max_pdop);
    fmt::print("  point uncertainty (3D, 1 sigma): mean {:.1f} um, max {:.1f} um\n", u_mean * 1e3, u_max * 1e3);
    for (size_t i = 0; i < result.stations.size(); ++i) {
      const Eigen::Vector3d& s = result.stations[i];
      const Eigen::Vector3d& u = result.station_u[i];
      fmt::print("  station {}: {:.4f}, {:.4f}, {:.4f} mm{}\n", problem.station_names[i], s.x(), s.y(), s.z(),
                 u.norm() > 0 ? fmt::format(" (u {:.1f}, {:.1f}, {:.1f} um)", u.x() * 1e3, u.y() * 1e3, u.z() * 1e3)
                              : std::string(args.self_calibrate ? " (held)" : ""));
    }
    if (truth_error) {
      fmt::print("  error against {}: mean {:.1f} um, max {:.1f} um\n", args.truth, truth_error->first * 1e3,
                 truth_error->second * 1e3);
    }
    for (const std::string& u : result.unobservable) fmt::print("  unobservable, held at its start: {}\n", u);
    std::string written;
    if (!args.output.empty()) written += args.output;
    if (for_verify) written += (written.empty() ? "" : " and ") + args.verify_readings + " (for fvm verify)";
    if (!written.empty()) fmt::print("  written {}\n", written);
  }
  if (!result.converged) {
    throw NotConvergedError(fmt::format("multilateration did not converge in {} iterations", result.iterations));
  }
}

}  // namespace

void RegisterMultilaterate(CLI::App& app) {
  auto args = std::make_shared<MultilaterateArgs>();
  CLI::App* sub = app.add_subcommand("multilaterate", "points from the ranges of several tracker stations (known or self-calibrated)");
  AddDetails(sub,
             "Locates every point of READINGS (id,station,range [,azimuth,elevation] [,x,y,z]; mm, rad) from the "
             "ranges of three or more stations, each weighted by the tracker's range noise (a + b * range): with "
             "known --stations each point by its own Gauss-Newton solve; with --self-calibrate the stations too "
             "(at least 4; frame: station 1 at the origin, station 2 on +x, station 3 in the xy plane; --stations then "
             "gives starting values, or the angles do); --angles adds azimuth and elevation (bundle adjustment, each "
             "station's rotation estimated). Reports the network's geometry (angles between lines of sight, PDOP) "
             "and each point's uncertainty. --verify-readings writes id,x,y,z,xt,yt,zt for fvm verify.");
  sub->add_option("READINGS", args->readings, "multilateration readings CSV: id,station,range (mm) [,azimuth,elevation (rad)] [,x,y,z]")
      ->required();
  sub->add_option("--stations", args->stations, "stations JSON {\"stations\": [{\"name\", \"x\", \"y\", \"z\"}]} (mm)");
  sub->add_flag("--self-calibrate", args->self_calibrate, "estimate the stations with the points (at least 4 stations per point)");
  sub->add_flag("--angles", args->angles, "use azimuth and elevation too (bundle adjustment)");
  sub->add_option("--tracker", args->tracker, "tracker noise model for the weights")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_option("-o,--output", args->output, "points CSV: id,x,y,z,u_x,u_y,u_z (mm)");
  sub->add_option("--nominal", args->nominal, "nominal machine coordinates id,x,y,z (e.g. points.csv of fvm simulate tracker)")
      ->check(CLI::ExistingFile);
  sub->add_option("--verify-readings", args->verify_readings,
                  "write the points as tracker readings id,x,y,z,xt,yt,zt for fvm verify (needs nominal coordinates)");
  sub->add_option("--truth", args->truth, "true positions id,x,y,z in the same frame (simulations: true_points.csv): report each point's error")
      ->check(CLI::ExistingFile);
  sub->add_flag("--json", args->json, "print the result as JSON (points, stations, range_rms_um, geometry, ...)");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --stations stations.json -o net\n"
      "  fvm multilaterate net/readings.csv --stations net/stations.json -o points.csv --verify-readings ml.csv\n"
      "  fvm multilaterate net/readings.csv --self-calibrate -o points.csv\n"
      "  fvm verify ml.csv --tool 0,0,100 --unweighted");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
