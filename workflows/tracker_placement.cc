#include "workflows/tracker_placement.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>

#include "artefacts/tracker_sight.h"
#include "core/input_error.h"
#include "core/progress.h"
#include "stage/monte_carlo.h"

namespace fvm::workflows {

int PlacementPositions(const TrackerPlacementOptions& options) { return options.steps * options.steps * options.steps + 1; }

TrackerPlacement PlaceTracker(const MachineProblem& problem, const MachineReference& reference_machine,
                              const TrackerPlacementOptions& options) {
  const stage::VerificationResult& reference = reference_machine.verification;
  const std::array<double, 6>& box = options.box;
  const stage::Calibration& truth = reference.identified.calibration;
  const bool estimate_pose = problem.options.instrument == stage::InstrumentPose::kEstimated;
  std::vector<PlacementCandidate> candidates;
  const int steps = options.steps;
  for (int i = 0; i < steps; ++i) {
    for (int j = 0; j < steps; ++j) {
      for (int k = 0; k < steps; ++k) {
        const Eigen::Vector3d t(i, j, k);
        PlacementCandidate c;
        for (int a = 0; a < 3; ++a) {
          const size_t lo = static_cast<size_t>(a), hi = static_cast<size_t>(3 + a);
          c.position[a] = steps == 1 ? 0.5 * (box[lo] + box[hi]) : box[lo] + (box[hi] - box[lo]) * t[a] / (steps - 1);
        }
        candidates.push_back(c);
      }
    }
  }
  PlacementCandidate current;
  current.position = reference.identified.pose.translation;
  current.current = true;
  candidates.push_back(current);

  const auto pose_at = [&](const Eigen::Vector3d& position) {
    stage::Pose p = reference.identified.pose;
    p.translation = position;
    return p;
  };
  const auto start = std::chrono::steady_clock::now();
  std::vector<char> visible(candidates.size(), 0);
  stage::ForEachRun(static_cast<int>(candidates.size()), options.monte_carlo.threads, [&](int index) {
    PlacementCandidate& c = candidates[static_cast<size_t>(index)];
    const stage::Pose pose = pose_at(c.position);
    artefacts::TrackerReadings seen = problem.readings;
    const std::vector<Eigen::Vector3d> predicted =
        stage::PredictedReadings(truth.layout, &truth.values, pose, problem.observations, problem.options.tool_offsets);
    for (size_t i = 0; i < predicted.size(); ++i) seen.points[i].measured = predicted[i];
    if (artefacts::PointsBeyondTrackerLimits(seen, pose).empty()) {
      visible[static_cast<size_t>(index)] = 1;
      for (const Eigen::Matrix3d& cov : stage::PredictedPointCovariances(truth, pose, estimate_pose, problem.observations,
                                                                         problem.options.tool_offsets, problem.noise)) {
        c.predicted_max_um = std::max(c.predicted_max_um, stage::U95OfCovariance(cov) * 1e3);
      }
    }
    if (options.on_position_done) options.on_position_done();
  });
  TrackerPlacement out;
  out.candidates = candidates.size() - 1;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (visible[i]) out.ranked.push_back(candidates[i]), out.visible_in_box += candidates[i].current ? 0 : 1;
  }
  if (out.visible_in_box == 0) {
    throw InputError(fmt::format("{}: from no position of the box can the tracker see every point; "
                                 "move the box away from the machine or below the points",
                                 options.box_name));
  }
  std::stable_sort(out.ranked.begin(), out.ranked.end(), [](const PlacementCandidate& a, const PlacementCandidate& b) {
    return a.predicted_max_um < b.predicted_max_um;
  });
  out.propagation_seconds = SecondsSince(start);

  // The Monte Carlo confirms the best few and the current position.
  stage::MonteCarloOptions mc;
  mc.runs = options.monte_carlo.runs;
  mc.seed = options.monte_carlo.seed;
  mc.threads = options.monte_carlo.threads;
  mc.weighted = problem.weighted;
  mc.truth_keeps_residuals = false;  // the readings' residuals belong to their own tracker's frame, not the moved one
  for (size_t r = 0; r < out.ranked.size(); ++r) {
    PlacementCandidate& c = out.ranked[r];
    if (!(r < static_cast<size_t>(options.confirm) || c.current)) continue;
    stage::VerificationResult at = reference;
    at.identified.pose = pose_at(c.position);
    at.initial_pose = at.identified.pose;
    stage::IdentificationOptions identification = problem.options;
    identification.pose = at.identified.pose;
    const std::vector<stage::MachineMonteCarloRun> runs = stage::MachineMonteCarlo(
        reference_machine.layout, at, problem.observations, {}, problem.noise, identification, mc);
    c.monte_carlo_max_um = 0;
    for (const stage::PointSpread& s : stage::PointSpreads(runs)) c.monte_carlo_max_um = std::max(c.monte_carlo_max_um, s.u95_mm * 1e3);
  }
  out.seconds = SecondsSince(start);
  return out;
}

}  // namespace fvm::workflows
