#include "artefacts/simulation/fvm_batch_simulation.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

#include "artefacts/geometry/artefact.h"
#include "artefacts/simulation/stage_truth.h"
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
  ParameterLayout layout =
      options.truth_terms.empty() ? stage::FvmModelLayout(options.truth_model) : stage::ComposeLayout(options.truth_terms);
  const Eigen::VectorXd tau = stage::PlausibleSizes(layout);
  // Stage errors grow with travel from the home position: offsets stay small (10 um), the terms that vary
  // along the axes carry the error ([Pérez thesis] section 5.7.2: up to 180-200 um over 200 mm). The guideways turn the
  // carriages by tens of microradians, a tenth of the plausible size the translations and squareness are drawn at: that
  // turn is what each stitched frame keeps from its first tile (stitched_frame.h).
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> values(static_cast<size_t>(layout.NumFree()));
  for (int i = 0; i < layout.NumFree(); ++i) {
    const auto& c = layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(i)]))];
    const stage::ErrorKind kind = stage::GetErrorTerm(c.term).kind;
    const bool offset = c.power == 0 && kind == stage::ErrorKind::kTranslation;
    values[static_cast<size_t>(i)] = normal(rng) * (offset ? 0.02 : kind == stage::ErrorKind::kRotation ? 0.03 : 0.3) * tau[i];
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

std::vector<std::string> HiddenEffectNames() {
  return {"thermal_drift", "higher_order", "reference_anchor", "z_coupling", "outliers", "scale"};
}

bool FvmBatchOptions::Hides(std::string_view effect) const {
  std::string_view rest = hidden_effect;
  while (!rest.empty()) {
    const size_t comma = rest.find(',');
    if (rest.substr(0, comma) == effect) return true;
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return false;
}

void FvmBatchOptions::Check() const {
  if (!(periodic_um >= 0) || !(period_mm > 0)) throw std::invalid_argument("the periodic error must be >= 0 um over a period > 0 mm");
  const std::pair<const char*, double> sizes[] = {
      {"--mean-error-um", mean_error_um},   {"--noise-um", noise_um},       {"--pitch-error-um", pitch_error_um},
      {"--validation-placements", double(validation_placements)},          {"--height-step-mm", height_step_mm},
      {"--effect-size", effect_size},       {"--drift-tau-min", drift_tau_min}};
  for (const auto& [option, value] : sizes) {
    if (!(value >= 0)) throw std::invalid_argument(fmt::format("{} is {}: simulation sizes must be non-negative", option, value));
  }
  const std::vector<std::string> names = HiddenEffectNames();
  std::stringstream list(hidden_effect);
  for (std::string name; std::getline(list, name, ',');) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      throw std::invalid_argument("unknown hidden effect '" + name + "': use " + fmt::format("{}", fmt::join(names, ", ")) +
                                  ", or several joined by commas");
    }
  }
}

namespace {

double EffectSize(const FvmBatchOptions& o, double default_size) { return o.effect_size > 0 ? o.effect_size : default_size; }

// Adds terms to the truth, keeping the drawn values of the coefficients it already had.
void ExtendTruth(FvmBatchTruth& truth, const std::vector<std::pair<std::string, double>>& added_terms_and_values,
                 int order_of_added) {
  std::map<std::string, double> by_name;
  const std::vector<std::string> old_names = truth.layout.FreeNames();
  for (size_t i = 0; i < old_names.size(); ++i) by_name[old_names[i]] = truth.values[i];
  std::vector<std::pair<std::string, double>> new_coefficients;
  for (const auto& [term, value] : added_terms_and_values) {
    const int index = *stage::FindErrorTerm(term);
    const stage::TermSpec spec = truth.layout.term(index);
    const int order = spec.present ? spec.order + 1 : order_of_added;
    truth.layout.SetTerm(term, stage::Basis::kPower, order);  // the existing coefficients keep their values
    new_coefficients.emplace_back(term + std::to_string(order), value);
  }
  for (const auto& [name, value] : new_coefficients) by_name[name] = value;
  truth.values.clear();
  for (const std::string& name : truth.layout.FreeNames()) truth.values.push_back(by_name.count(name) ? by_name[name] : 0.0);
}

}  // namespace

SimulatedFvmBatch SimulateFvmBatch(const FvmBatchOptions& options) {
  options.Check();
  std::mt19937_64 rng(options.seed);
  SimulatedFvmBatch out{Batch{}, DrawTruth(options, rng)};
  // Hidden effects draw from their own generator, so a batch without one is the same bytes as before.
  std::mt19937_64 effect_rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_int_distribution<int> sign(0, 1);
  const auto signed_size = [&](double size) { return sign(effect_rng) ? size : -size; };
  if (options.Hides("higher_order")) {
    // The next power of xTx, reaching the size at the far end of the travel (u = q / 100 = -2).
    const int order = out.truth.layout.term(*stage::FindErrorTerm("xTx")).order + 1;
    ExtendTruth(out.truth, {{"xTx", signed_size(EffectSize(options, 80.0) * 1e-3 / std::pow(2.0, order))}}, order);
  }
  if (options.Hides("z_coupling")) {
    std::vector<std::pair<std::string, double>> pitch_roll;
    // Only the sums xRx + yRx and xRy + yRy turn the tool against the part: Y's turns are half of X's, so that
    // signs drawn at random never cancel them to nothing.
    for (const char* term : {"xRx", "xRy", "yRx", "yRy"}) {
      pitch_roll.emplace_back(term, signed_size(EffectSize(options, 500.0) * 1e-6 * (term[0] == 'y' ? 0.5 : 1.0)));
    }
    for (auto& [term, value] : pitch_roll) {
      if (out.truth.layout.term(*stage::FindErrorTerm(term)).present) value = 0.0;  // already there: leave it
    }
    ExtendTruth(out.truth, pitch_roll, 0);
  }
  const ParameterLayout& layout = out.truth.layout;
  const std::vector<double>& values = out.truth.values;
  const StageTruth stage{layout, values, options.periodic_um, options.period_mm};

  // The uncalibrated bar: one set of pitch deviations for the whole batch (it is one physical artefact).
  std::normal_distribution<double> pitch(0.0, options.pitch_error_um * 1e-3);
  std::vector<Eigen::Vector3d> bar;
  for (const Calotte& c : CalotteBar17().calottes) bar.push_back(c.centre + Eigen::Vector3d(pitch(rng), pitch(rng), pitch(rng)));

  std::vector<PlacementPose> poses = IdentificationPoses();
  if (!options.same_start || options.Hides("reference_anchor")) {
    std::uniform_real_distribution<double> shift(0.0, options.Hides("reference_anchor") ? EffectSize(options, 30.0) : 30.0);
    for (PlacementPose& p : poses) p.start += Eigen::Vector2d(shift(rng), -shift(rng));
  }
  for (const PlacementPose& p : ValidationPoses(options.validation_placements, rng)) poses.push_back(p);

  std::normal_distribution<double> noise(0.0, options.noise_um * 1e-3);
  std::uniform_real_distribution<double> tilt(-1.5e-3, 1.5e-3);  // the bar never lies perfectly flat
  const auto noisy = [&](Eigen::Vector3d v) { return Eigen::Vector3d(v.x() + noise(rng), v.y() + noise(rng), v.z() + noise(rng)); };
  const Eigen::Vector3d drift_mm_per_s = options.Hides("thermal_drift")
                                             ? Eigen::Vector3d(Eigen::Vector3d(1.0, -0.5, 0.3) * EffectSize(options, 3.0) * 1e-3 / 60.0)
                                             : Eigen::Vector3d::Zero();
  const double scale = options.Hides("scale") ? signed_size(EffectSize(options, 300.0) * 1e-6) : 0.0;
  for (size_t p = 0; p < poses.size(); ++p) {
    const PlacementPose& pose = poses[p];
    const double c = std::cos(pose.angle_rad), s = std::sin(pose.angle_rad);
    const double tilt_along = tilt(rng);
    // On a wedge the bar rises from calotte 1 to 17 by -step, 0 or +step, in turn.
    const double rise_per_mm = options.height_step_mm * (static_cast<double>(p % 3) - 1.0) / 160.0;
    Placement placement, exact;
    placement.name = pose.name;
    std::vector<Eigen::Vector3d> commands;
    for (size_t i = 0; i < bar.size(); ++i) {
      const Eigen::Vector3d& b = bar[i];
      const Eigen::Vector3d truth(pose.start.x() + c * b.x() - s * b.y(), pose.start.y() + s * b.x() + c * b.y(),
                                  -50.0 + b.z() + (tilt_along + rise_per_mm) * b.x());
      commands.push_back(stage.Inverse(truth));
    }
    const Eigen::Vector3d anchor = stage::FirstTile(commands);
    const stage::FirstTileFrame frame = stage::MakeFirstTileFrame(options.stitched_frame, layout, values.data(), anchor, nullptr);
    for (size_t i = 0; i < commands.size(); ++i) {
      const bool backwards = options.serpentine && p % 2 == 1;
      const double t = options.seconds_per_centre * static_cast<double>(backwards ? commands.size() - 1 - i : i);
      placement.ids.push_back(static_cast<int>(i) + 1);
      const double drift_s = options.drift_tau_min > 0 ? options.drift_tau_min * 60.0 * (1.0 - std::exp(-t / (options.drift_tau_min * 60.0))) : t;
      placement.free.push_back(noisy(commands[i]) + drift_mm_per_s * drift_s);
      exact.free.push_back(commands[i] + drift_mm_per_s * drift_s);
      Eigen::Vector3d stitched = frame.Stitched(stage.Forward(commands[i]));
      if (scale != 0.0) stitched.head<2>() = anchor.head<2>() + (1.0 + scale) * (stitched - anchor).head<2>();
      placement.stitched.push_back(noisy(stitched));
      exact.stitched.push_back(stitched);
      placement.t_s.push_back(t);
    }
    if (options.Hides("outliers") && pose.name == "id-y") {
      // Three failed sphere fits: a burr or a missing patch pulls the fitted centre sideways.
      std::uniform_int_distribution<size_t> which(0, commands.size() - 1);
      std::uniform_real_distribution<double> direction(-1.0, 1.0);
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d d = Eigen::Vector3d(direction(effect_rng), direction(effect_rng), 0.2 * direction(effect_rng)).normalized();
        placement.free[which(effect_rng)] += d * EffectSize(options, 80.0) * 1e-3;
      }
    }
    exact.name = placement.name;
    exact.ids = placement.ids;
    exact.t_s = placement.t_s;
    out.exact.placements.push_back(std::move(exact));
    out.batch.placements.push_back(std::move(placement));
  }
  out.batch.has_roles = true;
  for (const PlacementPose& p : poses) (p.name.starts_with("id-") ? out.batch.identify : out.batch.validate).push_back(p.name);
  out.batch.lens = "5x";
  const std::vector<Placement> exact_placements = std::move(out.exact.placements);
  out.exact = out.batch;
  out.exact.placements = exact_placements;
  return out;
}

}  // namespace fvm::artefacts
