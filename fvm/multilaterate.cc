// fvm multilaterate READINGS.csv --stations S.json -o POINTS.csv [--self-calibrate] [--angles]: points from the
// ranges (and angles) of several tracker stations, with the stations known or calibrated with the points
// (workflows/multilaterate.h).

#include <fmt/core.h>

#include <optional>

#include "core/exit_codes.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "stage/tracker.h"
#include "workflows/multilaterate_summary.h"

namespace fvm::cli {
namespace {

struct MultilaterateCommand {
  workflows::MultilaterateOptions options;
  std::string output, verify_readings;
  bool json = false;
};

void Run(const MultilaterateCommand& c) {
  const workflows::MultilaterateOptions& o = c.options;
  o.Check();
  const workflows::Multilateration m = workflows::Multilaterate(o);
  // Nominal coordinates for fvm verify: from the readings' x,y,z or --nominal.
  const auto nominal = workflows::NominalCoordinates(m, o.nominal);
  std::optional<artefacts::TrackerReadings> for_verify;
  if (!c.verify_readings.empty()) for_verify = workflows::VerifyReadings(m, o, nominal, o.nominal, c.verify_readings);
  std::optional<stage::ResidualSummary> truth_error;
  if (!o.truth.empty()) truth_error = workflows::ErrorAgainstTruth(m, o.truth);

  // Outputs only after every check.
  if (!c.output.empty()) artefacts::WriteMultilateratedPoints(c.output, m.Points(), workflows::PointsFileComments(m, o));
  if (for_verify) artefacts::WriteTrackerReadings(c.verify_readings, *for_verify);
  std::string written = c.output;
  if (for_verify) written += (written.empty() ? "" : " and ") + c.verify_readings + " (for fvm verify)";
  workflows::Summary summary = workflows::Summarize(m, o, truth_error, o.truth, written);
  AddSortedPath(summary.json, "readings", o.readings);
  fmt::print("{}", c.json ? summary.json.dump(2) + "\n" : summary.text);
  if (!m.result.converged) {
    throw NotConvergedError(fmt::format("multilateration did not converge in {} iterations", m.result.iterations));
  }
}

}  // namespace

void RegisterMultilaterate(CLI::App& app) {
  auto command = std::make_shared<MultilaterateCommand>();
  workflows::MultilaterateOptions& o = command->options;
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
  sub->add_option("READINGS", o.readings, "multilateration readings CSV: id,station,range (mm) [,azimuth,elevation (rad)] [,x,y,z]")
      ->required();
  sub->add_option("--stations", o.stations, "stations JSON {\"stations\": [{\"name\", \"x\", \"y\", \"z\"}]} (mm)");
  sub->add_flag("--self-calibrate", o.self_calibrate, "estimate the stations with the points (at least 4 stations per point)");
  sub->add_flag("--angles", o.angles, "use azimuth and elevation too (bundle adjustment)");
  sub->add_option("--tracker", o.tracker, "tracker noise model for the weights")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_option("-o,--output", command->output, "points CSV: id,x,y,z,u_x,u_y,u_z (mm)");
  sub->add_option("--nominal", o.nominal, "nominal machine coordinates id,x,y,z (e.g. points.csv of fvm simulate tracker)")
      ->check(CLI::ExistingFile);
  sub->add_option("--verify-readings", command->verify_readings,
                  "write the points as tracker readings id,x,y,z,xt,yt,zt with their covariances cxx..czz (mm^2) for fvm verify "
                  "(needs nominal coordinates)");
  sub->add_option("--truth", o.truth, "true positions id,x,y,z in the same frame (simulations: true_points.csv): report each point's error")
      ->check(CLI::ExistingFile);
  sub->add_flag("--json", command->json, "print the result as JSON (points, stations, range_rms_um, geometry, ...)");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --stations stations.json -o net\n"
      "  fvm multilaterate net/readings.csv --stations net/stations.json -o points.csv --verify-readings ml.csv\n"
      "  fvm multilaterate net/readings.csv --self-calibrate -o points.csv\n"
      "  fvm verify ml.csv --tool 0,0,100");
  sub->callback([command] { Run(*command); });
}

}  // namespace fvm::cli
