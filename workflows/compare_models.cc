#include "workflows/compare_models.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "artefacts/batch_observations.h"
#include "core/input_error.h"
#include "core/statistics.h"
#include "stage/fvm_stage_models.h"

namespace fvm::workflows {
namespace {

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

// Validation residuals on held-out placements: the batch.json roles, or each placement left out in turn.
ModelScore Score(const std::string& model, const artefacts::Batch& batch, const IdentifySettings& settings) {
  const stage::MeasurementSet identify = artefacts::Observations(batch, batch.identify);
  ModelScore score{model, stage::FvmModelLayout(model).NumFree(), IdentifyModel({model, ""}, identify, settings), {}, {}, {}, {}, 0.0, 0.0, 0.0};
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
      add(IdentifyModel({model, ""}, artefacts::Observations(batch, rest), settings), artefacts::Observations(batch, {left_out}));
    }
  }
  stage::ValidationStats& v = score.validation;
  static_cast<stage::ResidualSummary&>(v) = stage::Summarize(v.residuals);
  if (v.count > 0) v.predicted_rms_mm = std::sqrt(v.predicted_rms_mm / v.count);
  score.distance_error_rms_mm = Rms(score.distance_errors);
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

}  // namespace

ModelComparison CompareModels(const artefacts::Batch& batch, const std::vector<std::string>& models,
                              const IdentifySettings& settings, const std::function<void(const std::string&)>& on_model) {
  ModelComparison c;
  for (const std::string& model : models) {
    if (on_model) on_model(model);
    c.scores.push_back(Score(model, batch, settings));
  }
  c.validation_placements = !batch.validate.empty();
  c.recommendation = Recommend(c.scores, batch.has_roles && !batch.validate.empty());
  return c;
}

void CompareOptions::Check() const {
  if (models.empty()) throw InputError("--models: no model given; name one or more of " + JoinNames(stage::FvmModelNames()));
  const std::vector<std::string> published = stage::FvmModelNames();
  for (const std::string& m : models) {
    if (std::find(published.begin(), published.end(), m) == published.end()) {
      throw InputError(fmt::format("--models: '{}' is not one of {}", m, JoinNames(published)));
    }
  }
  settings.Check();
}

ModelComparison CompareModels(const artefacts::Batch& batch, const CompareOptions& options,
                              const std::function<void(const std::string&)>& on_model) {
  options.Check();
  return CompareModels(batch, options.models, options.settings, on_model);
}

}  // namespace fvm::workflows
