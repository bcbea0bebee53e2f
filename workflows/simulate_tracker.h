#pragma once
// fvm simulate tracker as a job: the points of a machine-tool verification planned over the travel (and their
// G-code), and with a machine truth (random from a seed, or a file) the laser-tracker readings of them: one tracker
// at a pose, or several stations for a multilateration [IJSIMM 2016]. Every part draws from its own seed of the
// SplitMix64 sequence of `seed` (core/random.h SequenceSeed: 0 the machine, 1 the cloud, 2 the noise, 3 the
// validation cloud).

#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/tracker_readings.h"
#include "artefacts/machine_truth.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "stage/residual_summary.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// mesh:SX,SY,SZ | cloud:SX,SY,SZ (steps, mm) | diagonals:N (points per body diagonal).
struct PointPlan {
  std::string kind = "mesh";
  Eigen::Vector3d step{500, 500, 400};
  int per_diagonal = 0;
  std::string Text() const;  // as the option is written: "mesh:500,500,400"
  // The points over `ws`; a cloud draws from `seed`.
  std::vector<artefacts::PlannedPoint> Plan(const artefacts::Workspace& ws, std::uint64_t seed) const;
};

struct SimulateTrackerOptions {
  artefacts::Workspace machine;    // the axes' travel (mm): 2500 x 1500 x 1200 from the origin
  std::string chain = "XFYZ";
  PointPlan points;
  Eigen::Vector3d tool{0, 0, 100};  // reflector offset in the last tool axis' frame (mm)
  // The tracker in the machine frame: X,Y,Z (mm), intrinsic XYZ Euler angles (deg); [IJSIMM 2016] Table I position 4.
  Eigen::Vector3d pose_mm{1100, -1000, 600}, pose_euler_deg{63, 14, 35};
  std::string errors;              // machine truth JSON; empty: a random machine from `seed`
  std::optional<std::uint64_t> seed;  // none (and no errors): the plan alone, its cloud drawn from seed 1
  double mean_error_um = 35.0;     // of the random machine
  std::string tracker = "published";  // noise preset
  double dwell_s = 6.0, feed_mm_min = 2000.0;  // the G-code program's
  std::optional<PointPlan> validation;  // noise-free readings of other points
  std::string stations;            // several stations (JSON, machine frame) instead of one tracker
  bool WithTruth() const { return seed.has_value() || !errors.empty(); }
  // Names the option a value no simulation takes (--chain, --tracker, --stations and --validation without a truth).
  void Check() const;
};

struct SimulatedTracker {
  std::vector<artefacts::PlannedPoint> points;
  std::string where;  // "mesh:500,500,400 on 2500 x 1500 x 1200 mm from (0,0,0) mm"
  std::string points_csv, program;  // points.csv, program.nc
  // With a truth: one tracker's readings, or the stations' (then stations.json and true_points.csv in their frame).
  std::optional<artefacts::TrackerReadings> readings;
  std::optional<artefacts::MultilaterationReadings> station_readings;
  std::string stations_json, true_points_csv;
  size_t stations = 0;
  std::optional<artefacts::TrackerReadings> validation;
  std::optional<nlohmann::json> truth;  // truth.json
  stage::ResidualSummary error;         // the machine's volumetric error at the points
  std::optional<stage::ResidualSummary> validation_error;
};

// Everything checked before anything is written: points the tracker (or a station) cannot see are an InputError
// naming the pose and the first points.
SimulatedTracker SimulateTracker(const SimulateTrackerOptions& options);

// Writes DIR/points.csv and program.nc, and with a truth readings.csv, validation.csv, truth.json (stations:
// stations.json and true_points.csv), each atomically; creates DIR.
void WriteFiles(const SimulatedTracker& simulated, const std::filesystem::path& dir);

// The line the command prints; `output`: the directory the front end writes.
Summary Summarize(const SimulatedTracker& simulated, const SimulateTrackerOptions& options, const std::string& output);

}  // namespace fvm::workflows
