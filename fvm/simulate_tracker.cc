// fvm simulate tracker -o DIR: a machine-tool verification plan (points, G-code) and, with a truth, its simulated
// laser-tracker readings (one tracker, or several stations for fvm multilaterate).

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "artefacts/io/machine_truth_file.h"
#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/tracker_readings.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "stage/multilateration_start.h"
#include "stage/pose.h"
#include "stage/tracker.h"

namespace fvm::cli {
namespace {

// mesh:SX,SY,SZ | cloud:SX,SY,SZ | diagonals:N
struct PointSpec {
  std::string kind;
  Eigen::Vector3d step = Eigen::Vector3d::Zero();
  int per_diagonal = 0;
};

PointSpec ParsePointSpec(std::string_view text, const std::string& flag) {
  const size_t colon = text.find(':');
  PointSpec spec;
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

std::vector<artefacts::PlannedPoint> Plan(const PointSpec& spec, const artefacts::Workspace& ws, std::uint64_t seed) {
  if (spec.kind == "mesh") return artefacts::PlanMesh(ws, spec.step);
  if (spec.kind == "cloud") return artefacts::PlanCloud(ws, spec.step, seed);
  return artefacts::PlanDiagonals(ws, spec.per_diagonal);
}

// Independent streams from one --seed (SplitMix64): the truth, the cloud, the noise and the validation cloud
// never share draws.
std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

struct SimulateTrackerArgs {
  std::string output;
  std::string machine = "2500x1500x1200";
  std::string chain = "XFYZ";
  std::string points = "mesh:500,500,400";
  std::string tool = "0,0,100";
  std::string pose = "1100,-1000,600,63,14,35";
  std::string errors;
  std::uint64_t seed = 1;
  bool seed_given = false;
  double mean_error_um = 35.0;
  std::string tracker = "published";
  double dwell_s = 6.0;
  double feed_mm_min = 2000.0;
  std::string validation;
  std::string stations;
};

std::string PointsCsv(const std::vector<artefacts::PlannedPoint>& points, const std::string& comment) {
  std::string out = "# " + comment + "\n" + CsvLine({"id", "x", "y", "z", "approach"});
  for (const auto& p : points) {
    out += CsvLine({p.id, FormatShortest(p.nominal.x()), FormatShortest(p.nominal.y()), FormatShortest(p.nominal.z()),
                    p.approach});
  }
  return out;
}

std::string JoinNumbers(const Eigen::Vector3d& v) {
  return FormatShortest(v.x()) + "," + FormatShortest(v.y()) + "," + FormatShortest(v.z());
}

// A clear error when the tracker cannot see some points from its pose.
void CheckSight(const artefacts::TrackerReadings& readings, const stage::Pose& pose, const std::string& what,
                const std::string& pose_text) {
  const std::vector<std::string> beyond = artefacts::PointsBeyondTrackerLimits(readings, pose);
  if (beyond.empty()) return;
  const artefacts::TrackerLimits limits;
  std::string list;
  for (size_t i = 0; i < beyond.size() && i < 5; ++i) list += "\n  " + beyond[i];
  if (beyond.size() > 5) list += fmt::format("\n  ... and {} more", beyond.size() - 5);
  throw InputError(fmt::format("{} of {} {} are out of the tracker's sight from --pose {} (elevation {:+.0f} .. "
                               "{:+.0f} deg against the horizontal, range up to {:.0f} m):{}\nmove the tracker "
                               "(--pose) or plan other points",
                               beyond.size(), readings.points.size(), what, pose_text, limits.min_elevation_deg,
                               limits.max_elevation_deg, limits.max_range_mm / 1000.0, list));
}

// --stations: the same machine read by several stations for fvm multilaterate. The stations file is in the
// machine frame; what the run writes is in the stations' 3-2-1 frame (station 1 at the origin, 2 on +x, 3 in the
// xy plane), the frame a self-calibration finds, so known and self-calibrated stations give comparable points.
void RunStations(const SimulateTrackerArgs& args, const stage::AxisChain& chain, const artefacts::Workspace& ws,
                 const artefacts::MachineTruth& truth, const std::vector<artefacts::PlannedPoint>& points,
                 const stage::TrackerNoise& noise, const std::string& where) {
  const std::vector<artefacts::Station> machine_stations = artefacts::ReadStations(args.stations);
  if (machine_stations.size() < 3) {
    throw InputError(fmt::format("{}: {} station(s); multilateration needs at least 3", args.stations, machine_stations.size()));
  }
  std::vector<Eigen::Vector3d> positions;
  for (const auto& s : machine_stations) positions.push_back(s.position);
  Eigen::Matrix3d to_frame;
  Eigen::Vector3d shift;
  try {
    stage::ThreeTwoOneFrame(positions, &to_frame, &shift);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}", args.stations, e.what()));
  }
  const auto targets = artefacts::TrueToolPoints(chain, truth, points);
  // Sight: every station, levelled, against the tracker's limits.
  for (const artefacts::Station& s : machine_stations) {
    artefacts::TrackerReadings seen;
    for (const auto& [id, p] : targets) {
      artefacts::TrackerReading r;
      r.id = id;
      r.measured = p - s.position;
      seen.points.push_back(r);
    }
    stage::Pose at;
    at.translation = s.position;
    CheckSight(seen, at, "points", "station " + s.name);
  }
  std::vector<Eigen::Vector3d> nominal;
  for (const auto& p : points) nominal.push_back(p.nominal);
  artefacts::MultilaterationReadings readings =
      artefacts::SimulateMultilaterationReadings(machine_stations, targets, nominal, noise, StreamSeed(args.seed, 2));
  readings.comments = {
      "fvm simulate tracker: multilateration readings of a simulated machine tool, one row per point and station",
      fmt::format("chain {}, tool offset {} mm, points {}; {} stations of {} (levelled, azimuth 0 along machine +x)",
                  args.chain, args.tool, where, machine_stations.size(), args.stations),
      fmt::format("tracker {} (range sigma {} mm + {} mm/mm, azimuth {} rad, elevation {} rad), seed {}", noise.name,
                  FormatShortest(noise.range_sigma_mm), FormatShortest(noise.range_sigma_per_mm),
                  FormatShortest(noise.azimuth_sigma_rad), FormatShortest(noise.elevation_sigma_rad), args.seed),
      "range (mm), azimuth, elevation (rad) in each station's frame; x,y,z: commanded machine coordinates (mm)"};
  std::vector<artefacts::Station> frame_stations = machine_stations;
  for (auto& s : frame_stations) s.position = to_frame * s.position + shift;
  // Exactly the 3-2-1 frame, not its rounding.
  frame_stations[0].position.setZero();
  frame_stations[1].position.tail<2>().setZero();
  frame_stations[2].position.z() = 0.0;
  std::string true_points = "# fvm simulate tracker: true tool points in the stations' frame (station 1 at the origin, "
                            "2 on +x, 3 in the xy plane), mm\n" + CsvLine({"id", "x", "y", "z"});
  for (const auto& [id, p] : targets) {
    const Eigen::Vector3d f = to_frame * p + shift;
    true_points += CsvLine({id, FormatShortest(f.x()), FormatShortest(f.y()), FormatShortest(f.z())});
  }
  // The stations' frame in the machine frame, as fvm verify's tracker pose would find it.
  stage::Pose frame_pose;
  frame_pose.translation = machine_stations[0].position;
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(to_frame.transpose()));
  frame_pose.rotation = aa.angle() * aa.axis();
  std::optional<artefacts::TrackerReadings> validation;
  if (!args.validation.empty()) {
    auto others = Plan(ParsePointSpec(args.validation, "--validation"), ws, StreamSeed(args.seed, 3));
    for (auto& p : others) p.id[0] = 'V';
    stage::AxisChain in_frame = chain;
    in_frame.instrument = frame_pose;
    validation = artefacts::SimulateTrackerReadings(in_frame, truth, others, stage::TrackerNoise::Preset("none"), 0);
    validation->comments = {"fvm simulate tracker: noise-free validation points in the stations' frame (tracker none)",
                            fmt::format("chain {}, tool offset {} mm, points {}", args.chain, args.tool, args.validation)};
  }
  const stage::ResidualSummary error = artefacts::VolumetricErrorSummary(chain, truth, points);
  nlohmann::json json = nlohmann::json::parse(artefacts::MachineTruthJson(truth));
  json["what"] = "machine-tool truth of fvm simulate tracker --stations: the 21 error terms (mm, rad) as functions of q - "
                 "workspace min (mm), and the stations";
  json["chain"] = args.chain;
  json["tool_offset_mm"] = {chain.tool_offset.x(), chain.tool_offset.y(), chain.tool_offset.z()};
  json["stations_machine_frame"] = nlohmann::json::parse(artefacts::StationsJson(machine_stations))["stations"];
  json["stations_frame"] = nlohmann::json::parse(artefacts::StationsJson(frame_stations))["stations"];
  json["stations_frame_pose"] = {{"translation_mm", {frame_pose.translation.x(), frame_pose.translation.y(), frame_pose.translation.z()}},
                                 {"rotation_vector_rad", {frame_pose.rotation.x(), frame_pose.rotation.y(), frame_pose.rotation.z()}}};
  json["tracker"] = {{"name", noise.name},
                     {"range_sigma_mm", noise.range_sigma_mm},
                     {"range_sigma_per_mm", noise.range_sigma_per_mm},
                     {"azimuth_sigma_rad", noise.azimuth_sigma_rad},
                     {"elevation_sigma_rad", noise.elevation_sigma_rad}};
  json["points"] = {{"spec", args.points}, {"count", points.size()}, {"mean_error_um", error.mean_um()}, {"max_error_um", error.max_um()}};
  json["seed"] = args.seed;
  const std::filesystem::path dir(args.output);
  std::filesystem::create_directories(dir);
  WriteFileAtomically(dir / "points.csv", PointsCsv(points, "fvm simulate tracker: " + where));
  WriteFileAtomically(dir / "program.nc", artefacts::GCodeProgram(points, args.dwell_s, args.feed_mm_min));
  artefacts::WriteMultilaterationReadings(dir / "readings.csv", readings);
  WriteFileAtomically(dir / "stations.json", artefacts::StationsJson(frame_stations));
  WriteFileAtomically(dir / "true_points.csv", true_points);
  if (validation) artefacts::WriteTrackerReadings(dir / "validation.csv", *validation);
  WriteFileAtomically(dir / "truth.json", json.dump(2) + "\n");
  fmt::print("simulated {} points ({}, {}) read by {} stations into {}: readings.csv ({} rows), stations.json and "
             "true_points.csv in the stations' frame; initial volumetric error mean {:.1f} um; tracker {}, seed {}\n",
             points.size(), where, args.chain, machine_stations.size(), args.output, readings.rows.size(), error.mean_um(),
             noise.name, args.seed);
}

void RunTracker(const SimulateTrackerArgs& args) {
  // The validators have checked every text; parsing again cannot fail.
  const artefacts::Workspace ws = ParseMachine(args.machine);
  const PointSpec spec = ParsePointSpec(args.points, "--points");
  const auto tool = ParseNumbers(args.tool, 3, "--tool", "0,0,100");
  const auto pose6 = ParseNumbers(args.pose, 6, "--pose", "1100,-1000,600,63,14,35");
  const bool with_truth = args.seed_given || !args.errors.empty();
  if (!args.stations.empty() && !with_truth) {
    throw CLI::ValidationError("--stations", "needs a machine truth to simulate: give --seed N or --errors FILE.json");
  }
  if (!args.validation.empty() && !with_truth) {
    throw CLI::ValidationError("--validation", "needs a machine truth to simulate: give --seed N or --errors FILE.json");
  }
  stage::AxisChain chain = stage::AxisChain::Parse(args.chain);
  chain.tool_offset = Eigen::Vector3d(tool[0], tool[1], tool[2]);
  const Eigen::Vector3d euler_deg(pose6[3], pose6[4], pose6[5]);
  chain.instrument = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(pose6[0], pose6[1], pose6[2]), euler_deg);
  const stage::TrackerNoise noise = stage::TrackerNoise::Preset(args.tracker);

  const auto points = Plan(spec, ws, StreamSeed(args.seed, 1));
  const std::filesystem::path dir(args.output);
  const std::string where = fmt::format("{} on {} x {} x {} mm from ({}) mm", args.points, ws.max.x() - ws.min.x(),
                                        ws.max.y() - ws.min.y(), ws.max.z() - ws.min.z(), JoinNumbers(ws.min));
  if (!with_truth) {
    std::filesystem::create_directories(dir);
    WriteFileAtomically(dir / "points.csv", PointsCsv(points, "fvm simulate tracker: " + where));
    WriteFileAtomically(dir / "program.nc", artefacts::GCodeProgram(points, args.dwell_s, args.feed_mm_min));
    fmt::print("planned {} points ({}) into {}: points.csv, program.nc ({:.0f} min of dwell); no readings without a "
               "machine truth: give --seed N or --errors FILE.json\n",
               points.size(), where, args.output, points.size() * args.dwell_s / 60.0);
    return;
  }

  // The truth, the readings and their checks, all before anything is written.
  const artefacts::MachineTruth truth = args.errors.empty()
                                            ? artefacts::RandomMachineTruth(chain, ws, StreamSeed(args.seed, 0), args.mean_error_um)
                                            : artefacts::ReadMachineTruth(args.errors, ws);
  if (!args.stations.empty()) {
    RunStations(args, chain, ws, truth, points, noise, where);
    return;
  }
  artefacts::TrackerReadings noise_free;
  artefacts::TrackerReadings readings =
      artefacts::SimulateTrackerReadings(chain, truth, points, noise, StreamSeed(args.seed, 2), &noise_free);
  CheckSight(noise_free, *chain.instrument, "points", args.pose);
  const stage::ResidualSummary error = artefacts::VolumetricErrorSummary(chain, truth, points);

  std::vector<std::string> comments = {
      "fvm simulate tracker: laser-tracker readings of a simulated machine tool",
      fmt::format("chain {}, tool offset {} mm, points {}", args.chain, args.tool, where),
      fmt::format("tracker {} (range sigma {} mm + {} mm/mm, azimuth {} rad, elevation {} rad) at pose {} (mm, XYZ "
                  "Euler deg)",
                  noise.name, FormatShortest(noise.range_sigma_mm), FormatShortest(noise.range_sigma_per_mm),
                  FormatShortest(noise.azimuth_sigma_rad), FormatShortest(noise.elevation_sigma_rad), args.pose),
      args.errors.empty() ? fmt::format("truth: random, seed {}, mean volumetric error {} um over an 11 x 11 x 11 workspace grid",
                                        args.seed, FormatShortest(args.mean_error_um))
                          : fmt::format("truth: {}, noise seed {}", args.errors, args.seed),
      "x,y,z: commanded machine coordinates (mm); xt,yt,zt: tracker frame (mm)"};
  readings.comments = comments;

  std::optional<artefacts::TrackerReadings> validation;
  std::optional<stage::ResidualSummary> validation_error;
  if (!args.validation.empty()) {
    auto others = Plan(ParsePointSpec(args.validation, "--validation"), ws, StreamSeed(args.seed, 3));
    for (auto& p : others) p.id[0] = 'V';  // V0001...: never mistaken for an identification point
    validation = artefacts::SimulateTrackerReadings(chain, truth, others, stage::TrackerNoise::Preset("none"), 0);
    CheckSight(*validation, *chain.instrument, "validation points", args.pose);
    validation->comments = comments;
    validation->comments[0] = "fvm simulate tracker: noise-free validation points of the same machine (tracker none)";
    validation->comments[1] = fmt::format("chain {}, tool offset {} mm, points {}", args.chain, args.tool, args.validation);
    validation_error = artefacts::VolumetricErrorSummary(chain, truth, others);
  }

  nlohmann::json json = nlohmann::json::parse(artefacts::MachineTruthJson(truth));
  json["what"] = "machine-tool truth of fvm simulate tracker: the 21 error terms (mm, rad) as functions of q - "
                 "workspace min (mm); give this file back as --errors to simulate the same machine";
  json["chain"] = args.chain;
  json["tool_offset_mm"] = tool;
  const Eigen::Vector3d rotation = chain.instrument->rotation;
  json["tracker_pose"] = {{"translation_mm", {pose6[0], pose6[1], pose6[2]}},
                          {"euler_xyz_deg", {pose6[3], pose6[4], pose6[5]}},
                          {"rotation_vector_rad", {rotation.x(), rotation.y(), rotation.z()}}};
  json["tracker"] = {{"name", noise.name},
                     {"range_sigma_mm", noise.range_sigma_mm},
                     {"range_sigma_per_mm", noise.range_sigma_per_mm},
                     {"azimuth_sigma_rad", noise.azimuth_sigma_rad},
                     {"elevation_sigma_rad", noise.elevation_sigma_rad}};
  json["points"] = {{"spec", args.points}, {"count", points.size()}, {"mean_error_um", error.mean_um()},
                    {"max_error_um", error.max_um()}};
  json["seed"] = args.seed;
  json["errors_file"] = args.errors.empty() ? nlohmann::json(nullptr) : nlohmann::json(args.errors);
  if (args.errors.empty()) json["requested_mean_error_um"] = args.mean_error_um;
  json["mean_error_um"] = error.mean_um();
  json["max_error_um"] = error.max_um();
  if (validation) {
    json["validation"] = {{"spec", args.validation}, {"count", validation->points.size()},
                          {"mean_error_um", validation_error->mean_um()}, {"max_error_um", validation_error->max_um()}};
  }

  std::filesystem::create_directories(dir);
  WriteFileAtomically(dir / "points.csv", PointsCsv(points, "fvm simulate tracker: " + where));
  WriteFileAtomically(dir / "program.nc", artefacts::GCodeProgram(points, args.dwell_s, args.feed_mm_min));
  artefacts::WriteTrackerReadings(dir / "readings.csv", readings);
  if (validation) artefacts::WriteTrackerReadings(dir / "validation.csv", *validation);
  WriteFileAtomically(dir / "truth.json", json.dump(2) + "\n");
  // The random machine is scaled on a fixed workspace grid, not on these points, so that a mesh and a cloud of
  // the same seed measure the same machine ([IJSIMM 2016] Tables II and III); corners weigh more in a coarse mesh.
  const std::string scaled =
      args.errors.empty() ? fmt::format(" (machine scaled to {} um mean over an 11 x 11 x 11 workspace grid)",
                                        FormatShortest(args.mean_error_um))
                          : std::string();
  fmt::print("simulated {} points ({}, {}) into {}: initial volumetric error mean {:.1f} um, max {:.1f} um{}; "
             "tracker {}, seed {}{}\n",
             points.size(), where, args.chain, args.output, error.mean_um(), error.max_um(), scaled, noise.name, args.seed,
             validation ? fmt::format("; {} validation points (mean {:.1f} um)", validation->points.size(),
                                      validation_error->mean_um())
                        : std::string());
}

}  // namespace

void RegisterSimulateTracker(CLI::App* simulate) {
  auto args = std::make_shared<SimulateTrackerArgs>();
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
  sub->add_option("-o,--output", args->output, "directory to write (created if needed)")->required();
  sub->add_option("--machine", args->machine, "axis travels LXxLYxLZ in mm, optionally @X0,Y0,Z0 (the origin, default 0)")
      ->check(MachineCheck())
      ->capture_default_str();
  sub->add_option("--chain", args->chain, "axis chain in F notation (part axes left of F, tool axes right): XFYZ, YXFZ, ...")
      ->check(Parses([](const std::string& t) { stage::AxisChain::Parse(t); }, "CHAIN"))
      ->capture_default_str();
  sub->add_option("--points", args->points, "mesh:SX,SY,SZ | cloud:SX,SY,SZ (steps in mm; cloud seeded by --seed) | diagonals:N")
      ->check(PointSpecCheck("--points"))
      ->capture_default_str();
  sub->add_option("--tool", args->tool, "tool (reflector) offset X,Y,Z in mm, in the last tool axis' frame")
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->capture_default_str();
  sub->add_option("--pose", args->pose,
                  "tracker pose in the machine frame: X,Y,Z (mm) and intrinsic XYZ Euler angles A,B,C (deg); default "
                  "[IJSIMM 2016] Table I position 4")
      ->check(PoseCheck("--pose"))
      ->capture_default_str();
  CLI::Option* errors = sub->add_option("--errors", args->errors, "machine truth as JSON (format: docs/tutorials/machine-tool.md)")
                            ->check(CLI::ExistingFile);
  CLI::Option* seed = sub->add_option("--seed", args->seed,
                                      "random machine, cloud and tracker noise (same seed, same bytes); with --errors: "
                                      "the cloud and noise only")
                          ->check(Within(kSeed))
                          ->capture_default_str();
  sub->add_option("--mean-error-um", args->mean_error_um, "mean volumetric error of the random machine (um)")
      ->check(Within(1e-3, 1e5, "um"))
      ->capture_default_str()
      ->excludes(errors);
  sub->add_option("--tracker", args->tracker, "tracker noise preset (docs/tutorials/machine-tool.md)")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_option("--dwell-s", args->dwell_s, "dwell at each point in the program (s)")
      ->check(Within(0.0, 3600.0, "s"))
      ->capture_default_str();
  sub->add_option("--feed-mm-min", args->feed_mm_min, "feed between points in the program (mm/min; 0: rapid moves)")
      ->check(Within(0.0, 1e6, "mm/min"))
      ->capture_default_str();
  sub->add_option("--validation", args->validation, "noise-free readings of other points, same SPEC forms as --points")
      ->check(PointSpecCheck("--validation"));
  sub->add_option("--stations", args->stations,
                  "several stations instead of one tracker: JSON {\"stations\": [{\"name\", \"x\", \"y\", \"z\"}]} "
                  "in the machine frame (mm); writes readings.csv for fvm multilaterate, stations.json and "
                  "true_points.csv in the stations' frame (--pose is then unused)")
      ->check(CLI::ExistingFile);
  sub->footer("Example:\n  fvm simulate tracker --machine 2500x1500x1200 --chain XFYZ --points mesh:500,500,400 "
              "--tool 0,0,100 -o plan --seed 1 --validation mesh:100,100,100\n"
              "  fvm simulate tracker --seed 1 --stations stations.json -o net   # for fvm multilaterate");
  sub->callback([args, seed] {
    SimulateTrackerArgs a = *args;
    a.seed_given = seed->count() > 0;
    RunTracker(a);
  });
}

}  // namespace fvm::cli
