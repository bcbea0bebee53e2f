#pragma once
// Where to put the tracker ([Pérez 2019 Sensors] section 3): tracker positions on a grid of a box (machine frame,
// mm; the estimated orientation kept: the noise is the same in any orientation of the tracker's frame), those from
// which the tracker sees every point, ranked by the largest 95 % radius over the readings' points that covariance
// propagation predicts (stage::PredictedPointCovariances); the best few and the readings' own position confirmed
// by the Monte Carlo.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "workflows/machine_problem.h"
#include "workflows/uncertainty.h"

namespace fvm::workflows {

struct TrackerPlacementOptions {
  std::array<double, 6> box{};  // X0,Y0,Z0,X1,Y1,Z1 (mm, machine frame)
  std::string box_name;         // how the box was given, first in its refusal ("--place-tracker 1000,...")
  int steps = 4;                // grid positions per axis (1: the box's centre)
  int confirm = 3;              // best positions the Monte Carlo confirms (the readings' own is always confirmed)
  MonteCarloSettings monte_carlo;          // runs, seed, threads of each confirmation (its on_run_done unused)
  std::function<void()> on_position_done;  // after each position's propagation, from any thread; may be empty
};

// steps^3 grid positions and the readings' own.
int PlacementPositions(const TrackerPlacementOptions& options);

struct PlacementCandidate {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double predicted_max_um = 0;     // the largest predicted 95 % radius over the points
  double monte_carlo_max_um = -1;  // the largest Monte Carlo 95 % radius; < 0: not confirmed
  bool current = false;            // the readings' own tracker position
};

struct TrackerPlacement {
  std::vector<PlacementCandidate> ranked;  // the positions that see every point, best first (stable: grid order)
  size_t candidates = 0;                   // grid positions in the box
  size_t visible_in_box = 0;               // of those, the ones that see every point
  double propagation_seconds = 0, seconds = 0;
};

// Refuses a box from no position of which the tracker sees every point (InputError naming the box).
TrackerPlacement PlaceTracker(const MachineProblem& problem, const MachineReference& reference,
                              const TrackerPlacementOptions& options);

}  // namespace fvm::workflows
