// fvm multilaterate READINGS.csv --stations S.json -o POINTS.csv [--self-calibrate] [--angles]: points from the
// ranges (and angles) of several tracker stations, with the stations known or calibrated with the points.

#include <fmt/core.h>

#include <nlohmann/json.hpp>
#include <optional>

#include "core/exit_codes.h"
#include "fvm/commands.h"
#include "stage/tracker.h"
#include "workflows/multilaterate.h"

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

void Run(const MultilaterateArgs& args) {
  workflows::MultilaterateOptions job;
  job.readings = args.readings;
  job.stations = args.stations;
  job.self_calibrate = args.self_calibrate;
  job.angles = args.angles;
  job.tracker = args.tracker;
  const workflows::Multilateration m = workflows::Multilaterate(job);
  const stage::MultilaterationProblem& problem = m.problem;
  const stage::MultilaterationResult& result = m.result;
  const stage::MultilaterationOptions& options = m.options;
  const std::string mode = m.Mode();

  // Nominal coordinates for fvm verify: from the readings' x,y,z or --nominal.
  const auto nominal = workflows::NominalCoordinates(m, args.nominal);
  std::optional<artefacts::TrackerReadings> for_verify;
  if (!args.verify_readings.empty()) {
    for_verify = workflows::VerifyReadings(m, job, nominal, args.nominal, args.verify_readings);
  }

  // Summaries.
  const std::vector<artefacts::MultilateratedPoint> points = m.Points();
  nlohmann::json jpoints = nlohmann::json::array();
  for (const artefacts::MultilateratedPoint& p : points) {
    jpoints.push_back({{"id", p.id}, {"x", p.position.x()}, {"y", p.position.y()}, {"z", p.position.z()},
                       {"u_x", p.u.x()}, {"u_y", p.u.y()}, {"u_z", p.u.z()}});
  }
  const double u_mean = m.u_mean_mm, u_max = m.u_max_mm;
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
  std::optional<stage::ResidualSummary> truth_error;
  if (!args.truth.empty()) {
    truth_error = workflows::ErrorAgainstTruth(m, args.truth);
    doc["truth_error"] = {{"mean_um", truth_error->mean_mm * 1e3}, {"rms_um", truth_error->rms_mm * 1e3},
                          {"max_um", truth_error->max_mm * 1e3}};
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
      fmt::print("  error against {}: mean {:.1f} um, max {:.1f} um\n", args.truth, truth_error->mean_mm * 1e3,
                 truth_error->max_mm * 1e3);
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
             "known --stations each point by its own least-squares solve; with --self-calibrate the stations too "
             "(at least 4; frame: station 1 at the origin, station 2 on +x, station 3 in the xy plane; --stations then "
             "gives starting values, or the angles do); --angles adds azimuth and elevation (bundle adjustment, each "
             "station's rotation estimated). Reports the network's geometry (angles between lines of sight, PDOP) "
             "and each point's uncertainty. --verify-readings writes id,x,y,z,xt,yt,zt and each point's covariance "
             "cxx..czz (mm^2) for fvm verify, which weighs each point by it.");
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
                  "write the points as tracker readings id,x,y,z,xt,yt,zt with their covariances cxx..czz (mm^2) for fvm verify "
                  "(needs nominal coordinates)");
  sub->add_option("--truth", args->truth, "true positions id,x,y,z in the same frame (simulations: true_points.csv): report each point's error")
      ->check(CLI::ExistingFile);
  sub->add_flag("--json", args->json, "print the result as JSON (points, stations, range_rms_um, geometry, ...)");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --stations stations.json -o net\n"
      "  fvm multilaterate net/readings.csv --stations net/stations.json -o points.csv --verify-readings ml.csv\n"
      "  fvm multilaterate net/readings.csv --self-calibrate -o points.csv\n"
      "  fvm verify ml.csv --tool 0,0,100");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
