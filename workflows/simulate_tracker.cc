#include "workflows/simulate_tracker.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>

#include "artefacts/io/machine_truth_file.h"
#include "artefacts/tracker_sight.h"
#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "core/random.h"
#include "stage/multilateration_start.h"
#include "stage/pose.h"
#include "stage/tracker.h"

namespace fvm::workflows {
namespace {

// The parts of a simulation, each drawing from its own seed (core/random.h SequenceSeed).
enum Stream : std::uint64_t { kMachineStream = 0, kCloudStream = 1, kNoiseStream = 2, kValidationStream = 3 };

std::string Joined(std::initializer_list<double> values) {
  std::string out;
  for (double v : values) {
    if (!out.empty()) out += ',';
    out += FormatShortest(v);
  }
  return out;
}

std::string ToolText(const SimulateTrackerOptions& o) { return Joined({o.tool.x(), o.tool.y(), o.tool.z()}); }

std::string PoseText(const SimulateTrackerOptions& o) {
  return Joined({o.pose_mm.x(), o.pose_mm.y(), o.pose_mm.z(), o.pose_euler_deg.x(), o.pose_euler_deg.y(), o.pose_euler_deg.z()});
}

std::string PointsCsv(const std::vector<artefacts::PlannedPoint>& points, const std::string& comment) {
  std::string out = "# " + comment + "\n" + CsvLine({"id", "x", "y", "z", "approach"});
  for (const auto& p : points) {
    out += CsvLine({p.id, FormatShortest(p.nominal.x()), FormatShortest(p.nominal.y()), FormatShortest(p.nominal.z()),
                    p.approach});
  }
  return out;
}

std::string NoiseText(const stage::TrackerNoise& noise) {
  return fmt::format("tracker {} (range sigma {} mm + {} mm/mm, azimuth {} rad, elevation {} rad)", noise.name,
                     FormatShortest(noise.range_sigma_mm), FormatShortest(noise.range_sigma_per_mm),
                     FormatShortest(noise.azimuth_sigma_rad), FormatShortest(noise.elevation_sigma_rad));
}

nlohmann::json NoiseJson(const stage::TrackerNoise& noise) {
  return {{"name", noise.name},
          {"range_sigma_mm", noise.range_sigma_mm},
          {"range_sigma_per_mm", noise.range_sigma_per_mm},
          {"azimuth_sigma_rad", noise.azimuth_sigma_rad},
          {"elevation_sigma_rad", noise.elevation_sigma_rad}};
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

// The validation points: V0001...: never mistaken for an identification point.
std::vector<artefacts::PlannedPoint> ValidationPoints(const SimulateTrackerOptions& o, std::uint64_t seed) {
  auto others = o.validation->Plan(o.machine, SequenceSeed(seed, kValidationStream));
  for (auto& p : others) p.id[0] = 'V';
  return others;
}

nlohmann::json TruthBase(const artefacts::MachineTruth& truth, const SimulateTrackerOptions& o, const std::string& what,
                         const stage::TrackerNoise& noise, const SimulatedTracker& out, std::uint64_t seed) {
  const stage::ResidualSummary& error = out.error;
  nlohmann::json json = nlohmann::json::parse(artefacts::MachineTruthJson(truth));
  json["what"] = what;
  json["chain"] = o.chain;
  json["tool_offset_mm"] = {o.tool.x(), o.tool.y(), o.tool.z()};
  json["tracker"] = NoiseJson(noise);
  json["points"] = {{"spec", o.points.Text()}, {"count", out.points.size()}, {"mean_error_um", error.mean_um()}, {"max_error_um", error.max_um()}};
  json["seed"] = seed;
  return json;
}

// The stations, read and checked: at least 3, not in a line; `to_frame`, `shift` take the machine frame to theirs.
std::vector<artefacts::Station> ReadStationsFrame(const std::string& path, Eigen::Matrix3d* to_frame, Eigen::Vector3d* shift) {
  const std::vector<artefacts::Station> stations = artefacts::ReadStations(path);
  if (stations.size() < 3) {
    throw InputError(fmt::format("{}: {} station(s); multilateration needs at least 3", path, stations.size()));
  }
  std::vector<Eigen::Vector3d> positions;
  for (const auto& s : stations) positions.push_back(s.position);
  try {
    stage::ThreeTwoOneFrame(positions, to_frame, shift);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
  return stations;
}

// Sight: every station, levelled, against the tracker's limits.
void CheckStationsSight(const std::vector<artefacts::Station>& stations,
                        const std::vector<std::pair<std::string, Eigen::Vector3d>>& targets) {
  for (const artefacts::Station& s : stations) {
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
}

// The stations in their own 3-2-1 frame, exactly (not its rounding), and the true tool points in it.
void StationsFrameFiles(const std::vector<artefacts::Station>& stations, const Eigen::Matrix3d& to_frame,
                        const Eigen::Vector3d& shift, const std::vector<std::pair<std::string, Eigen::Vector3d>>& targets,
                        SimulatedTracker& out) {
  std::vector<artefacts::Station> frame_stations = stations;
  for (auto& s : frame_stations) s.position = to_frame * s.position + shift;
  frame_stations[0].position.setZero();
  frame_stations[1].position.tail<2>().setZero();
  frame_stations[2].position.z() = 0.0;
  out.stations_json = artefacts::StationsJson(frame_stations);
  out.true_points_csv = "# fvm simulate tracker: true tool points in the stations' frame (station 1 at the origin, "
                        "2 on +x, 3 in the xy plane), mm\n" + CsvLine({"id", "x", "y", "z"});
  for (const auto& [id, p] : targets) {
    const Eigen::Vector3d f = to_frame * p + shift;
    out.true_points_csv += CsvLine({id, FormatShortest(f.x()), FormatShortest(f.y()), FormatShortest(f.z())});
  }
}

// --stations: the same machine read by several stations for fvm multilaterate. The stations file is in the machine
// frame; what the run writes is in the stations' 3-2-1 frame (station 1 at the origin, 2 on +x, 3 in the xy
// plane), the frame a self-calibration finds, so known and self-calibrated stations give comparable points.
void SimulateStations(const SimulateTrackerOptions& o, const stage::AxisChain& chain, const artefacts::MachineTruth& truth,
                      const stage::TrackerNoise& noise, std::uint64_t seed, SimulatedTracker& out) {
  Eigen::Matrix3d to_frame;
  Eigen::Vector3d shift;
  const std::vector<artefacts::Station> stations = ReadStationsFrame(o.stations, &to_frame, &shift);
  const auto targets = artefacts::TrueToolPoints(chain, truth, out.points);
  CheckStationsSight(stations, targets);
  std::vector<Eigen::Vector3d> nominal;
  for (const auto& p : out.points) nominal.push_back(p.nominal);
  out.station_readings = artefacts::SimulateMultilaterationReadings(stations, targets, nominal, noise, SequenceSeed(seed, kNoiseStream));
  out.station_readings->comments = {
      "fvm simulate tracker: multilateration readings of a simulated machine tool, one row per point and station",
      fmt::format("chain {}, tool offset {} mm, points {}; {} stations of {} (levelled, azimuth 0 along machine +x)",
                  o.chain, ToolText(o), out.where, stations.size(), o.stations),
      fmt::format("{}, seed {}", NoiseText(noise), seed),
      "range (mm), azimuth, elevation (rad) in each station's frame; x,y,z: commanded machine coordinates (mm)"};
  out.stations = stations.size();
  StationsFrameFiles(stations, to_frame, shift, targets, out);
  // The stations' frame in the machine frame, as fvm verify's tracker pose would find it.
  stage::Pose frame_pose;
  frame_pose.translation = stations[0].position;
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(to_frame.transpose()));
  frame_pose.rotation = aa.angle() * aa.axis();
  if (o.validation) {
    stage::AxisChain in_frame = chain;
    in_frame.instrument = frame_pose;
    out.validation = artefacts::SimulateTrackerReadings(in_frame, truth, ValidationPoints(o, seed), stage::TrackerNoise::Preset("none"), 0);
    out.validation->comments = {"fvm simulate tracker: noise-free validation points in the stations' frame (tracker none)",
                                fmt::format("chain {}, tool offset {} mm, points {}", o.chain, ToolText(o), o.validation->Text())};
  }
  out.error = artefacts::VolumetricErrorSummary(chain, truth, out.points);
  nlohmann::json json = TruthBase(truth, o,
                                  "machine-tool truth of fvm simulate tracker --stations: the 21 error terms (mm, rad) as "
                                  "functions of q - workspace min (mm), and the stations",
                                  noise, out, seed);
  json["stations_machine_frame"] = nlohmann::json::parse(artefacts::StationsJson(stations))["stations"];
  json["stations_frame"] = nlohmann::json::parse(out.stations_json)["stations"];
  json["stations_frame_pose"] = {{"translation_mm", {frame_pose.translation.x(), frame_pose.translation.y(), frame_pose.translation.z()}},
                                 {"rotation_vector_rad", {frame_pose.rotation.x(), frame_pose.rotation.y(), frame_pose.rotation.z()}}};
  out.truth = json;
}

// One tracker at the pose: its readings with noise, the validation points without.
void SimulateOneTracker(const SimulateTrackerOptions& o, const stage::AxisChain& chain, const artefacts::MachineTruth& truth,
                        const stage::TrackerNoise& noise, std::uint64_t seed, SimulatedTracker& out) {
  artefacts::TrackerReadings noise_free;
  out.readings = artefacts::SimulateTrackerReadings(chain, truth, out.points, noise, SequenceSeed(seed, kNoiseStream), &noise_free);
  CheckSight(noise_free, *chain.instrument, "points", PoseText(o));
  out.error = artefacts::VolumetricErrorSummary(chain, truth, out.points);
  out.readings->comments = {
      "fvm simulate tracker: laser-tracker readings of a simulated machine tool",
      fmt::format("chain {}, tool offset {} mm, points {}", o.chain, ToolText(o), out.where),
      fmt::format("{} at pose {} (mm, XYZ Euler deg)", NoiseText(noise), PoseText(o)),
      o.errors.empty() ? fmt::format("truth: random, seed {}, mean volumetric error {} um over an 11 x 11 x 11 workspace grid",
                                     seed, FormatShortest(o.mean_error_um))
                       : fmt::format("truth: {}, noise seed {}", o.errors, seed),
      "x,y,z: commanded machine coordinates (mm); xt,yt,zt: tracker frame (mm)"};
  if (o.validation) {
    const std::vector<artefacts::PlannedPoint> others = ValidationPoints(o, seed);
    out.validation = artefacts::SimulateTrackerReadings(chain, truth, others, stage::TrackerNoise::Preset("none"), 0);
    CheckSight(*out.validation, *chain.instrument, "validation points", PoseText(o));
    out.validation->comments = out.readings->comments;
    out.validation->comments[0] = "fvm simulate tracker: noise-free validation points of the same machine (tracker none)";
    out.validation->comments[1] = fmt::format("chain {}, tool offset {} mm, points {}", o.chain, ToolText(o), o.validation->Text());
    out.validation_error = artefacts::VolumetricErrorSummary(chain, truth, others);
  }
  nlohmann::json json = TruthBase(truth, o,
                                  "machine-tool truth of fvm simulate tracker: the 21 error terms (mm, rad) as functions of "
                                  "q - workspace min (mm); give this file back as --errors to simulate the same machine",
                                  noise, out, seed);
  const Eigen::Vector3d rotation = chain.instrument->rotation;
  json["tracker_pose"] = {{"translation_mm", {o.pose_mm.x(), o.pose_mm.y(), o.pose_mm.z()}},
                          {"euler_xyz_deg", {o.pose_euler_deg.x(), o.pose_euler_deg.y(), o.pose_euler_deg.z()}},
                          {"rotation_vector_rad", {rotation.x(), rotation.y(), rotation.z()}}};
  json["errors_file"] = o.errors.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.errors);
  if (o.errors.empty()) json["requested_mean_error_um"] = o.mean_error_um;
  json["mean_error_um"] = out.error.mean_um();
  json["max_error_um"] = out.error.max_um();
  if (out.validation) {
    json["validation"] = {{"spec", o.validation->Text()}, {"count", out.validation->points.size()},
                          {"mean_error_um", out.validation_error->mean_um()}, {"max_error_um", out.validation_error->max_um()}};
  }
  out.truth = json;
}

}  // namespace

std::string PointPlan::Text() const {
  if (kind == "diagonals") return fmt::format("diagonals:{}", per_diagonal);
  return kind + ":" + Joined({step.x(), step.y(), step.z()});
}

std::vector<artefacts::PlannedPoint> PointPlan::Plan(const artefacts::Workspace& ws, std::uint64_t seed) const {
  if (kind == "mesh") return artefacts::PlanMesh(ws, step);
  if (kind == "cloud") return artefacts::PlanCloud(ws, step, seed);
  return artefacts::PlanDiagonals(ws, per_diagonal);
}

void SimulateTrackerOptions::Check() const {
  try {
    machine.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("--machine: {}", e.what()));
  }
  for (const PointPlan* plan : {&points, validation ? &*validation : nullptr}) {
    if (plan == nullptr) continue;
    const std::string flag = plan == &points ? "--points" : "--validation";
    if (plan->kind != "mesh" && plan->kind != "cloud" && plan->kind != "diagonals") {
      throw InputError(fmt::format("{} {}: use mesh:SX,SY,SZ, cloud:SX,SY,SZ (steps in mm) or diagonals:N", flag, plan->kind));
    }
    if (plan->kind == "diagonals" ? plan->per_diagonal < 2 : !(plan->step.minCoeff() > 0.0)) {
      throw InputError(fmt::format("{} '{}': steps must be > 0 mm, diagonals at least 2 points", flag, plan->Text()));
    }
  }
  try {
    stage::AxisChain::Parse(chain);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("--chain {}: {}", chain, e.what()));
  }
  const std::vector<std::string> presets = stage::TrackerNoise::PresetNames();
  if (std::find(presets.begin(), presets.end(), tracker) == presets.end()) {
    throw InputError(fmt::format("--tracker {}: use one of {}", tracker, fmt::join(presets, ", ")));
  }
  if (!WithTruth() && !stations.empty()) throw InputError("--stations: needs a machine truth to simulate: give --seed N or --errors FILE.json");
  if (!WithTruth() && validation) throw InputError("--validation: needs a machine truth to simulate: give --seed N or --errors FILE.json");
}

SimulatedTracker SimulateTracker(const SimulateTrackerOptions& o) {
  const std::uint64_t seed = o.seed.value_or(1);
  stage::AxisChain chain = stage::AxisChain::Parse(o.chain);
  chain.tool_offset = o.tool;
  chain.instrument = stage::Pose::FromEulerXyzDegrees(o.pose_mm, o.pose_euler_deg);
  const stage::TrackerNoise noise = stage::TrackerNoise::Preset(o.tracker);
  const artefacts::Workspace& ws = o.machine;
  SimulatedTracker out;
  out.points = o.points.Plan(ws, SequenceSeed(seed, kCloudStream));
  out.where = fmt::format("{} on {} x {} x {} mm from ({}) mm", o.points.Text(), ws.max.x() - ws.min.x(), ws.max.y() - ws.min.y(),
                          ws.max.z() - ws.min.z(), Joined({ws.min.x(), ws.min.y(), ws.min.z()}));
  out.points_csv = PointsCsv(out.points, "fvm simulate tracker: " + out.where);
  out.program = artefacts::GCodeProgram(out.points, o.dwell_s, o.feed_mm_min);
  if (!o.WithTruth()) return out;
  // The truth, the readings and their checks, all before anything is written.
  const artefacts::MachineTruth truth = o.errors.empty()
                                            ? artefacts::RandomMachineTruth(chain, ws, SequenceSeed(seed, kMachineStream), o.mean_error_um)
                                            : artefacts::ReadMachineTruth(o.errors, ws);
  if (!o.stations.empty()) {
    SimulateStations(o, chain, truth, noise, seed, out);
  } else {
    SimulateOneTracker(o, chain, truth, noise, seed, out);
  }
  return out;
}

void WriteFiles(const SimulatedTracker& s, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  WriteFileAtomically(dir / "points.csv", s.points_csv);
  WriteFileAtomically(dir / "program.nc", s.program);
  if (s.readings) artefacts::WriteTrackerReadings(dir / "readings.csv", *s.readings);
  if (s.station_readings) {
    artefacts::WriteMultilaterationReadings(dir / "readings.csv", *s.station_readings);
    WriteFileAtomically(dir / "stations.json", s.stations_json);
    WriteFileAtomically(dir / "true_points.csv", s.true_points_csv);
  }
  if (s.validation) artefacts::WriteTrackerReadings(dir / "validation.csv", *s.validation);
  if (s.truth) WriteFileAtomically(dir / "truth.json", s.truth->dump(2) + "\n");
}

Summary Summarize(const SimulatedTracker& s, const SimulateTrackerOptions& o, const std::string& output) {
  const std::uint64_t seed = o.seed.value_or(1);
  Summary summary;
  if (!o.WithTruth()) {
    summary.text = fmt::format("planned {} points ({}) into {}: points.csv, program.nc ({:.0f} min of dwell); no readings without a "
                               "machine truth: give --seed N or --errors FILE.json\n",
                               s.points.size(), s.where, output, s.points.size() * o.dwell_s / 60.0);
  } else if (s.station_readings) {
    summary.text = fmt::format("simulated {} points ({}, {}) read by {} stations into {}: readings.csv ({} rows), stations.json and "
                               "true_points.csv in the stations' frame; initial volumetric error mean {:.1f} um; tracker {}, seed {}\n",
                               s.points.size(), s.where, o.chain, s.stations, output, s.station_readings->rows.size(),
                               s.error.mean_um(), o.tracker, seed);
  } else {
    // The random machine is scaled on a fixed workspace grid, not on these points, so that a mesh and a cloud of the
    // same seed measure the same machine ([IJSIMM 2016] Tables II and III); corners weigh more in a coarse mesh.
    const std::string scaled = o.errors.empty() ? fmt::format(" (machine scaled to {} um mean over an 11 x 11 x 11 workspace grid)",
                                                              FormatShortest(o.mean_error_um))
                                                : std::string();
    summary.text = fmt::format("simulated {} points ({}, {}) into {}: initial volumetric error mean {:.1f} um, max {:.1f} um{}; "
                               "tracker {}, seed {}{}\n",
                               s.points.size(), s.where, o.chain, output, s.error.mean_um(), s.error.max_um(), scaled, o.tracker, seed,
                               s.validation ? fmt::format("; {} validation points (mean {:.1f} um)", s.validation->points.size(),
                                                          s.validation_error->mean_um())
                                            : std::string());
  }
  if (s.truth) summary.json = *s.truth;
  return summary;
}

}  // namespace fvm::workflows
