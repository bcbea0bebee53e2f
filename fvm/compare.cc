// fvm compare BATCH [--models 9,15,27,42]: every model order side by side, and which one to trust.

#include <fmt/core.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "artefacts/io/batch.h"
#include "core/input_error.h"
#include "fvm/identify_options.h"
#include "artefacts/batch_observations.h"
#include "fvm/commands.h"
#include "stage/fvm_stage_models.h"
#include "stage/validation.h"

namespace fvm::cli {
namespace {

struct CompareArgs {
  std::string batch;
  std::vector<std::string> models = stage::FvmModelNames();
  bool json = false;
  workflows::IdentifySettings settings;
};

struct ModelScore {
  std::string model;
  int nominal = 0;  // parameters of the model as published
  stage::IdentificationResult identification;
  stage::ValidationStats validation;      // first-tile figure
  stage::FrameFreeStats rigid, distances;  // what no frame changes
  std::vector<double> distance_errors;
  double aic = 0, bic = 0;
};

// Two sets of held-out measurements as one: counts add, squares add.
void Pool(stage::FrameFreeStats& into, const stage::FrameFreeStats& more) {
  const double n = into.count + more.count;
  if (n == 0) return;
  const auto pooled = [&](double a, double b) { return std::sqrt((a * a * into.count + b * b * more.count) / n); };
  into.rms_mm = pooled(into.rms_mm, more.rms_mm);
  into.predicted_rms_mm = pooled(into.predicted_rms_mm, more.predicted_rms_mm);
  into.max_mm = std::max(into.max_mm, more.max_mm);
  into.count += more.count;
}

double Rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

// Validation residuals on held-out placements: the batch.json roles, or each placement left out in turn.
ModelScore Score(const std::string& model, const artefacts::Batch& batch, const workflows::IdentifySettings& settings) {
  const stage::MeasurementSet identify = artefacts::Observations(batch, batch.identify);
  ModelScore score{model, stage::FvmModelLayout(model).NumFree(), workflows::IdentifyModel({model, ""}, identify, settings), {}, {}, {}, {}};
  const stage::IdentificationResult& id = score.identification;
  const double m = 3.0 * static_cast<double>(id.residuals.size());
  double rss = 0;
  for (const Eigen::Vector3d& r : id.residuals) rss += r.squaredNorm();
  const double k = id.calibration.layout.NumFree();
  score.aic = m * std::log(rss / m) + 2 * k;
  score.bic = m * std::log(rss / m) + k * std::log(m);

  std::vector<stage::Observation> held_out;
  std::vector<Eigen::Vector3d> anchors;
  const auto add = [&](const stage::IdentificationResult& fit, const stage::MeasurementSet& set) {
    const stage::ValidationStats v = stage::Validate(&fit.calibration, set.observations, set.anchors, settings.Frame());
    Pool(score.rigid, stage::RigidValidation(&fit.calibration, set.observations));
    Pool(score.distances, stage::PairDistanceValidation(&fit.calibration, set.observations));
    for (const Eigen::Vector3d& r : v.residuals) score.validation.residuals.push_back(r);
    for (double d : stage::DistanceErrors(&fit.calibration, set.observations)) score.distance_errors.push_back(d);
    score.validation.predicted_rms_mm += v.predicted_rms_mm * v.predicted_rms_mm * v.count;
  };
  if (!batch.validate.empty()) {
    add(id, artefacts::Observations(batch, batch.validate));
  } else {
    for (const std::string& left_out : batch.identify) {
      std::vector<std::string> rest;
      for (const std::string& n : batch.identify) {
        if (n != left_out) rest.push_back(n);
      }
      if (rest.empty()) break;
      add(workflows::IdentifyModel({model, ""}, artefacts::Observations(batch, rest), settings), artefacts::Observations(batch, {left_out}));
    }
  }
  stage::ValidationStats& v = score.validation;
  static_cast<stage::ResidualSummary&>(v) = stage::Summarize(v.residuals);
  if (v.count > 0) v.predicted_rms_mm = std::sqrt(v.predicted_rms_mm / v.count);
  return score;
}

// The simplest model whose validation error after a rigid fit per placement (a figure no choice of frame
// changes) is within 10 % of the best one: more parameters must earn their place on held-out data, not on the
// identification residual.
std::string Recommend(const std::vector<ModelScore>& scores, bool has_roles) {
  const ModelScore* best = &scores.front();
  for (const ModelScore& s : scores) {
    if (s.rigid.rms_mm < best->rigid.rms_mm) best = &s;
  }
  const ModelScore* pick = best;
  for (const ModelScore& s : scores) {
    if (s.rigid.rms_mm <= 1.1 * best->rigid.rms_mm && s.nominal < pick->nominal) pick = &s;
  }
  std::string why = fmt::format("Use model {}: its validation error after a rigid fit per placement is {:.2f} um rms on {} "
                                "({} centres; {:.2f} um in the first tiles' frames)",
                                pick->model, pick->rigid.rms_mm * 1e3,
                                has_roles ? "the validation placements" : "placements left out in turn", pick->rigid.count,
                                pick->validation.rms_mm * 1e3);
  if (pick != best) {
    why += fmt::format(", within 10 % of the best (model {}, {:.2f} um) with fewer parameters", best->model, best->rigid.rms_mm * 1e3);
  } else {
    why += ", the lowest of all";
  }
  for (const ModelScore& s : scores) {
    if (&s != pick && &s != best && s.rigid.rms_mm > 1.5 * pick->rigid.rms_mm) {
      why += fmt::format("; model {} leaves {:.2f} um", s.model, s.rigid.rms_mm * 1e3);
    }
  }
  return why + ".";
}

void Run(const CompareArgs& args) {
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  std::vector<ModelScore> scores;
  for (const std::string& model : args.models) {
    if (!args.json) fmt::print(stderr, "  identifying model {} ...\n", model);
    scores.push_back(Score(model, batch, Threaded(args.settings)));
  }
  const std::string recommendation = Recommend(scores, batch.has_roles && !batch.validate.empty());
  nlohmann::json doc;
  doc["batch"] = args.batch;
  doc["validation_by"] = batch.validate.empty() ? "leave-one-placement-out" : "batch.json validate placements";
  doc["stitched_frame"] = args.settings.stitched_frame;
  const auto frame_free = [](const stage::FrameFreeStats& s) {
    return nlohmann::json{{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
                          {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
  };
  for (const ModelScore& s : scores) {
    const stage::IdentificationResult& id = s.identification;
    doc["models"].push_back({{"model", s.model},
                             {"n_params", s.nominal},
                             {"n_identified", id.calibration.layout.NumFree()},
                             {"fixed", id.fixed.size()},
                             {"identification", {{"mean_um", id.mean_mm * 1e3}, {"rms_um", id.rms_mm * 1e3}, {"max_um", id.max_mm * 1e3}}},
                             {"validation",
                              {{"centres", s.validation.count},
                               {"mean_um", s.validation.mean_mm * 1e3},
                               {"rms_um", s.validation.rms_mm * 1e3},
                               {"max_um", s.validation.max_mm * 1e3},
                               {"predicted_rms_um", s.validation.predicted_rms_mm * 1e3},
                               {"rigid", frame_free(s.rigid)},
                               {"distances", frame_free(s.distances)}}},
                             {"distance_error_um", {{"rms", Rms(s.distance_errors) * 1e3}}},
                             {"aic", s.aic},
                             {"bic", s.bic},
                             {"condition", id.condition_number},
                             {"converged", id.converged}});
  }
  doc["recommendation"] = recommendation;
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("fvm compare: {} (validation: {})\n\n", args.batch, doc["validation_by"].get<std::string>());
  // Frame-free figures first: the rigid fit per placement and the distances over all pairs, then the first tile's.
  fmt::print("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "model", "params",
             "fixed", "id rms", "rigid", "predicted", "dist", "predicted", "1st-tile", "max", "predicted", "AIC", "BIC", "cond");
  fmt::print("  {:>5} {:>6} {:>6} | {:>8} | {:>8} {:>9} | {:>8} {:>9} | {:>8} {:>8} {:>9} | {:>9} {:>9} {:>8}\n", "", "", "", "um",
             "rms um", "rms um", "rms um", "rms um", "rms um", "um", "rms um", "", "", "");
  for (const ModelScore& s : scores) {
    const stage::IdentificationResult& id = s.identification;
    fmt::print("  {:>5} {:>6} {:>6} | {:>8.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>9.2f} | {:>8.2f} {:>8.2f} {:>9.2f} | {:>9.1f} {:>9.1f} "
               "{:>8.3g}\n",
               s.model, s.nominal, id.fixed.size(), id.rms_mm * 1e3, s.rigid.rms_mm * 1e3, s.rigid.predicted_rms_mm * 1e3,
               s.distances.rms_mm * 1e3, s.distances.predicted_rms_mm * 1e3, s.validation.rms_mm * 1e3,
               s.validation.max_mm * 1e3, s.validation.predicted_rms_mm * 1e3, s.aic, s.bic, id.condition_number);
  }
  fmt::print("  (first tile: each placement in its first tile's {} frame)\n", args.settings.stitched_frame);
  fmt::print("\n  {}\n", recommendation);
}

}  // namespace

void RegisterCompare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = app.add_subcommand("compare", "every model order side by side on a batch, and which one to trust");
  sub->add_option("BATCH", args->batch, "batch directory (see 'fvm calibrate --help')")->required();
  sub->add_option("--models", args->models, "models to compare")->delimiter(',')->check(CLI::IsMember(stage::FvmModelNames()));
  sub->add_flag("--json", args->json, "print one JSON document on stdout");
  AddIdentifyOptions(*sub, args->settings);
  sub->footer("Example:\n  fvm compare samples/bar17 --models 15,27,42");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
