#include "artefacts/fvm_batch_simulation.h"

#include <fmt/core.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "artefacts/artefact.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "stage/inverse_model.h"

namespace fvm::artefacts {
namespace {

using stage::ParameterLayout;

// Stage error at q: where the part really is minus where the stage says it is.
Eigen::Vector3d StageError(const ParameterLayout& layout, const std::vector<double>& values, const Eigen::Vector3d& q) {
  return stage::Forward(layout, values, q) - q;
}

FvmBatchTruth DrawTruth(const FvmBatchOptions& options, std::mt19937_64& rng) {
  ParameterLayout layout = stage::FvmModelLayout(options.truth_model);
  const Eigen::VectorXd tau = stage::PlausibleSizes(layout);
  // Stage errors grow with travel from the home position: offsets stay small (10 um), the terms that vary
  // along the axes carry the error (000:7640: up to 180-200 um over 200 mm).
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> values(static_cast<size_t>(layout.NumFree()));
  for (int i = 0; i < layout.NumFree(); ++i) {
    const auto& c = layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(i)]))];
    const bool offset = c.power == 0 && stage::GetErrorTerm(c.term).kind == stage::ErrorKind::kTranslation;
    values[static_cast<size_t>(i)] = normal(rng) * (offset ? 0.02 : 0.3) * tau[i];
  }

  // Scale the draw so the mean error over the stage is the requested one (the model is nearly linear in its
  // coefficients, so two rescalings land within a fraction of a micrometre).
  const auto measure = [&](double* max_um) {
    double sum = 0;
    int count = 0;
    *max_um = 0;
    for (double x = -200; x <= 0; x += 10) {
      for (double y = -200; y <= 0; y += 10) {
        const double e = StageError(layout, values, {x, y, -50.0}).norm() * 1e3;
        sum += e;
        *max_um = std::max(*max_um, e);
        ++count;
      }
    }
    return sum / count;
  };
  double max_um = 0;
  for (int pass = 0; pass < 3; ++pass) {
    const double factor = options.mean_error_um / measure(&max_um);
    for (double& v : values) v *= factor;
  }
  FvmBatchTruth truth{layout, values, 0.0, 0.0};
  truth.mean_error_um = measure(&truth.max_error_um);
  return truth;
}

struct PlacementPose {
  std::string name;
  Eigen::Vector2d start;  // stage xy of calotte 1, mm
  double angle_rad;       // direction of the bar from calotte 1 to 17
};

std::vector<PlacementPose> IdentificationPoses() {
  const Eigen::Vector2d start(-185.0, -15.0);  // first tile at lowest x, highest y for all three
  return {{"id-x", start, 0.0}, {"id-y", start, -std::numbers::pi / 2}, {"id-oblique", start, -std::numbers::pi / 4}};
}

std::vector<PlacementPose> ValidationPoses(int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::uniform_real_distribution<double> coordinate(-195.0, -5.0);
  std::vector<PlacementPose> poses;
  while (static_cast<int>(poses.size()) < count) {
    const Eigen::Vector2d start(coordinate(rng), coordinate(rng));
    const double a = angle(rng);
    const Eigen::Vector2d end = start + 160.0 * Eigen::Vector2d(std::cos(a), std::sin(a));
    if (end.x() < -195.0 || end.x() > -5.0 || end.y() < -195.0 || end.y() > -5.0) continue;
    poses.push_back({fmt::format("val-{:02d}", poses.size() + 1), start, a});
  }
  return poses;
}

}  // namespace

void FvmBatchOptions::Check() const {
  if (!(mean_error_um >= 0) || !(noise_um >= 0) || !(pitch_error_um >= 0) || validation_placements < 0) {
    throw std::invalid_argument("simulation sizes must be non-negative");
  }
}

SimulatedFvmBatch SimulateFvmBatch(const FvmBatchOptions& options) {
  options.Check();
  std::mt19937_64 rng(options.seed);
  SimulatedFvmBatch out{Batch{}, DrawTruth(options, rng)};
  const ParameterLayout& layout = out.truth.layout;
  const std::vector<double>& values = out.truth.values;

  // The uncalibrated bar: one set of pitch deviations for the whole batch (it is one physical artefact).
  std::normal_distribution<double> pitch(0.0, options.pitch_error_um * 1e-3);
  std::vector<Eigen::Vector3d> bar;
  for (const Calotte& c : CalotteBar17().calottes) bar.push_back(c.centre + Eigen::Vector3d(pitch(rng), pitch(rng), pitch(rng)));

  std::vector<PlacementPose> poses = IdentificationPoses();
  if (!options.same_start) {
    std::uniform_real_distribution<double> shift(0.0, 30.0);
    for (PlacementPose& p : poses) p.start += Eigen::Vector2d(shift(rng), -shift(rng));
  }
  for (const PlacementPose& p : ValidationPoses(options.validation_placements, rng)) poses.push_back(p);

  std::normal_distribution<double> noise(0.0, options.noise_um * 1e-3);
  std::uniform_real_distribution<double> tilt(-1.5e-3, 1.5e-3);  // the bar never lies perfectly flat
  const auto noisy = [&](Eigen::Vector3d v) { return Eigen::Vector3d(v.x() + noise(rng), v.y() + noise(rng), v.z() + noise(rng)); };
  for (const PlacementPose& pose : poses) {
    const double c = std::cos(pose.angle_rad), s = std::sin(pose.angle_rad);
    const double tilt_along = tilt(rng);
    Placement placement;
    placement.name = pose.name;
    std::vector<Eigen::Vector3d> commands;
    for (size_t i = 0; i < bar.size(); ++i) {
      const Eigen::Vector3d& b = bar[i];
      const Eigen::Vector3d truth(pose.start.x() + c * b.x() - s * b.y(), pose.start.y() + s * b.x() + c * b.y(),
                                  -50.0 + b.z() + tilt_along * b.x());
      const stage::InverseResult command = stage::Inverse(layout, values.data(), truth);
      if (!command.converged) throw std::runtime_error("simulation: the stage model could not be inverted");
      commands.push_back(command.command);
    }
    const Eigen::Vector3d anchor = stage::FirstTile(commands);
    const Eigen::Vector3d anchor_error = StageError(layout, values, anchor);
    for (size_t i = 0; i < commands.size(); ++i) {
      placement.ids.push_back(static_cast<int>(i) + 1);
      placement.free.push_back(noisy(commands[i]));
      placement.stitched.push_back(noisy(stage::Forward(layout, values, commands[i]) - anchor_error));
      placement.t_s.push_back(options.seconds_per_centre * static_cast<double>(i));
    }
    out.batch.placements.push_back(std::move(placement));
  }
  out.batch.has_roles = true;
  for (const PlacementPose& p : poses) (p.name.starts_with("id-") ? out.batch.identify : out.batch.validate).push_back(p.name);
  out.batch.lens = "5x";
  return out;
}

}  // namespace fvm::artefacts
