// fvm simulate tracker -o DIR: a machine-tool verification plan (points, G-code) and, with a truth, its simulated
// laser-tracker readings (one tracker, or several stations for fvm multilaterate): workflows/simulate_tracker.h.

#include <fmt/core.h>

#include <optional>
#include <stdexcept>

#include "core/number_text.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "stage/tracker.h"
#include "workflows/simulate_tracker.h"

namespace fvm::cli {
namespace {

// mesh:SX,SY,SZ | cloud:SX,SY,SZ | diagonals:N
workflows::PointPlan ParsePointSpec(std::string_view text, const std::string& flag) {
  const size_t colon = text.find(':');
  workflows::PointPlan spec;
  spec.kind = std::string(text.substr(0, colon));
  const std::string_view rest = colon == std::string_view::npos ? std::string_view() : text.substr(colon + 1);
  if (spec.kind == "mesh" || spec.kind == "cloud") {
    const auto s = ParseNumbers(rest, 3, flag + " " + spec.kind, spec.kind + ":500,500,400 (steps in mm)", kStepMm);
    spec.step = Eigen::Vector3d(s[0], s[1], s[2]);
    if (!(spec.step.minCoeff() > 0.0)) throw std::invalid_argument(flag + " '" + std::string(text) + "': steps must be > 0 mm");
    return spec;
  }
  if (spec.kind == "diagonals") {
    const std::optional<std::int64_t> n = ParseInt(rest);
    if (!n || *n < 2 || *n > 100'000) {
      throw std::invalid_argument(flag + " '" + std::string(text) + "': diagonals:N with N = 2 .. 100000 points per body diagonal");
    }
    spec.per_diagonal = static_cast<int>(*n);
    return spec;
  }
  throw std::invalid_argument(flag + " '" + std::string(text) + "': use mesh:SX,SY,SZ, cloud:SX,SY,SZ (steps in mm) or diagonals:N");
}

CLI::Validator PointSpecCheck(const std::string& flag) {
  return ParsesWithin([flag](const std::string& t) { ParsePointSpec(t, flag); }, "mesh:V,V,V", kStepMm, "SPEC");
}

struct SimulateTrackerCommand {
  workflows::SimulateTrackerOptions options;
  std::string output;
};

void RunTracker(const SimulateTrackerCommand& c) {
  const workflows::SimulateTrackerOptions& o = c.options;
  if (!o.stations.empty() && !o.WithTruth()) {
    throw CLI::ValidationError("--stations", "needs a machine truth to simulate: give --seed N or --errors FILE.json");
  }
  if (o.validation && !o.WithTruth()) {
    throw CLI::ValidationError("--validation", "needs a machine truth to simulate: give --seed N or --errors FILE.json");
  }
  o.Check();
  const workflows::SimulatedTracker s = workflows::SimulateTracker(o);
  workflows::WriteFiles(s, c.output);
  fmt::print("{}", workflows::Summarize(s, o, c.output).text);
}

}  // namespace

void RegisterSimulateTracker(CLI::App* simulate) {
  auto command = std::make_shared<SimulateTrackerCommand>();
  workflows::SimulateTrackerOptions& o = command->options;
  CLI::App* sub = simulate->add_subcommand(
      "tracker", "machine-tool verification: point plan, G-code and simulated laser-tracker readings with their truth");
  AddDetails(sub,
             "Plans the points of a volumetric verification (mesh, cloud of [IJSIMM 2016] eq. 18 or body diagonals; X fastest, "
             "serpentine) and writes points.csv and program.nc (ISO G-code with a dwell per point). With --seed N (a "
             "random machine, its errors cubics plus ball-screw and long-wave sines that no cubic represents, scaled "
             "to --mean-error-um) or --errors FILE.json (your own truth) it also writes readings.csv (the tracker "
             "readings with the tracker's noise: --tracker), truth.json (the machine, the tracker and the errors; it "
             "can be given back as --errors) and, with --validation, validation.csv: noise-free readings of other "
             "points for checking an identification where it was not fitted. The tracker pose defaults to [IJSIMM 2016] "
             "Table I position 4. Points the tracker cannot see (elevation -60..+77 deg, range 40 m) stop the run.");
  sub->add_option("-o,--output", command->output, "directory to write (created if needed)")->required();
  sub->add_option_function<std::string>(
         "--machine", [&o](const std::string& t) { o.machine = ParseMachine(t); },
         "axis travels LXxLYxLZ in mm, optionally @X0,Y0,Z0 (the origin, default 0)")
      ->check(MachineCheck())
      ->default_str("2500x1500x1200");
  sub->add_option("--chain", o.chain, "axis chain in F notation (part axes left of F, tool axes right): XFYZ, YXFZ, ...")
      ->check(Parses([](const std::string& t) { stage::AxisChain::Parse(t); }, "CHAIN"))
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--points", [&o](const std::string& t) { o.points = ParsePointSpec(t, "--points"); },
         "mesh:SX,SY,SZ | cloud:SX,SY,SZ (steps in mm; cloud seeded by --seed) | diagonals:N")
      ->check(PointSpecCheck("--points"))
      ->default_str("mesh:500,500,400");
  sub->add_option_function<std::string>(
         "--tool", [&o](const std::string& t) { o.tool = ParseVector3(t, "--tool", "0,0,100"); },
         "tool (reflector) offset X,Y,Z in mm, in the last tool axis' frame")
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->default_str("0,0,100");
  sub->add_option_function<std::string>(
         "--pose",
         [&o](const std::string& t) {
           const auto pose6 = ParseNumbers(t, 6, "--pose", "1100,-1000,600,63,14,35");
           o.pose_mm = Eigen::Vector3d(pose6[0], pose6[1], pose6[2]);
           o.pose_euler_deg = Eigen::Vector3d(pose6[3], pose6[4], pose6[5]);
         },
                  "tracker pose in the machine frame: X,Y,Z (mm) and intrinsic XYZ Euler angles A,B,C (deg); default "
                  "[IJSIMM 2016] Table I position 4")
      ->check(PoseCheck("--pose"))
      ->default_str("1100,-1000,600,63,14,35");
  CLI::Option* errors = sub->add_option("--errors", o.errors, "machine truth as JSON (format: docs/tutorials/machine-tool.md)")
                            ->check(CLI::ExistingFile);
  sub->add_option_function<std::uint64_t>("--seed", [&o](std::uint64_t n) { o.seed = n; },
                                          "random machine, cloud and tracker noise (same seed, same bytes); with --errors: "
                                          "the cloud and noise only")
      ->check(Within(kSeed))
      ->default_str("1");
  sub->add_option("--mean-error-um", o.mean_error_um, "mean volumetric error of the random machine (um)")
      ->check(Within(1e-3, 1e5, "um"))
      ->capture_default_str()
      ->excludes(errors);
  sub->add_option("--tracker", o.tracker, "tracker noise preset (docs/tutorials/machine-tool.md)")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_option("--dwell-s", o.dwell_s, "dwell at each point in the program (s)")
      ->check(Within(0.0, 3600.0, "s"))
      ->capture_default_str();
  sub->add_option("--feed-mm-min", o.feed_mm_min, "feed between points in the program (mm/min; 0: rapid moves)")
      ->check(Within(0.0, 1e6, "mm/min"))
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--validation", [&o](const std::string& t) { o.validation = ParsePointSpec(t, "--validation"); },
         "noise-free readings of other points, same SPEC forms as --points")
      ->check(PointSpecCheck("--validation"));
  sub->add_option("--stations", o.stations,
                  "several stations instead of one tracker: JSON {\"stations\": [{\"name\", \"x\", \"y\", \"z\"}]} "
                  "in the machine frame (mm); writes readings.csv for fvm multilaterate, stations.json and "
                  "true_points.csv in the stations' frame (--pose is then unused)")
      ->check(CLI::ExistingFile);
  sub->footer("Example:\n  fvm simulate tracker --machine 2500x1500x1200 --chain XFYZ --points mesh:500,500,400 "
              "--tool 0,0,100 -o plan --seed 1 --validation mesh:100,100,100\n"
              "  fvm simulate tracker --seed 1 --stations stations.json -o net   # for fvm multilaterate");
  sub->callback([command] { RunTracker(*command); });
}

}  // namespace fvm::cli
