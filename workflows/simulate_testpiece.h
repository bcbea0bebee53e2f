#pragma once
// fvm simulate testpiece as a job: a test piece [Lorente 2021] cut by a machine with known errors and measured on a
// CMM, with the truth; optionally its series cut again with the tools that make the Z and Y yaws and the Z
// rotations observable, and a noise-free validation grid over the piece.

#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/geometry/machined_piece.h"
#include "artefacts/io/tracker_readings.h"
#include "stage/pose.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct SimulateTestPieceOptions {
  std::string piece;              // piece description JSON; empty: the published piece of [Lorente 2021]
  std::string errors;             // machine truth JSON (fvm simulate tracker's format); empty: see mean_error_um
  double mean_error_um = 0.0;     // > 0: a random machine (cubics + sines) of this mean error; 0: [Lorente 2021] Table 4
  std::string points = "all";     // all | pyramid ([Lorente 2021]'s 167-point test) | series (X1..Z3 only)
  std::string chain = "XFYZ";
  Eigen::Vector3d tool{0, 0, 100};  // mm
  stage::Pose datum = stage::Pose::FromEulerXyzDegrees({20, -15, 5}, {0.05, -0.1, 12});  // the piece on the CMM
  std::uint64_t seed = 1;         // random machine and CMM noise
  double noise_um = 1.0;          // CMM noise per coordinate
  bool proposed_series = false;   // the series cut again with three more tools
  std::optional<Eigen::Vector3d> validation_step;  // a noise-free grid over the piece with these steps (mm)
  // Names the option (--points, --chain, --noise-um, --mean-error-um) a value no simulation takes.
  void Check() const;
};

struct SimulatedTestPiece {
  std::vector<artefacts::PiecePoint> nominal;              // every probe point (the proposed series' as id-tK)
  artefacts::TrackerReadings measured;                     // id,x,y,z,xm,ym,zm [,tool]
  std::optional<artefacts::TrackerReadings> validation;    // the noise-free grid
  std::vector<Eigen::Vector3d> tools;                      // the tool, then the proposed series' tools
  nlohmann::json truth;                                    // truth.json: the errors, chain, tool, datum, noise, seed
};
SimulatedTestPiece SimulateTestPiece(const SimulateTestPieceOptions& options);

// Writes DIR/nominal.csv, measured.csv, validation.csv (with the grid) and truth.json, each atomically; creates DIR.
void WriteFiles(const SimulatedTestPiece& simulated, const std::filesystem::path& dir);

// What the command prints and its --json; `output`: the directory the front end writes (the text names it, the
// front end adds it to the JSON).
Summary Summarize(const SimulatedTestPiece& simulated, const SimulateTestPieceOptions& options, const std::string& output);

}  // namespace fvm::workflows
