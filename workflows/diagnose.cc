#include "workflows/diagnose.h"

#include <fmt/core.h>

#include <algorithm>
#include <map>

#include "artefacts/batch_observations.h"
#include "core/input_error.h"
#include "stage/fvm_stage_models.h"

namespace fvm::workflows {
namespace {

// Empty when the residuals are not the set's own (outliers taken out leave fewer, and no longer in step with it).
std::vector<double> DistanceErrors(const stage::MeasurementSet& set, const std::vector<Eigen::Vector3d>& residuals) {
  std::vector<double> errors;
  if (residuals.size() != set.observations.size()) return errors;
  std::map<int, size_t> first;
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const auto [it, inserted] = first.emplace(set.observations[i].group, i);
    if (inserted) continue;
    const Eigen::Vector3d d = set.observations[i].measured - set.observations[it->second].measured;
    if (d.norm() > 0) errors.push_back(d.normalized().dot(residuals[i] - residuals[it->second]));
  }
  return errors;
}

}  // namespace

void DiagnoseOptions::Check() const {
  const std::vector<std::string> published = stage::FvmModelNames();
  if (model.terms.empty() && std::find(published.begin(), published.end(), model.model) == published.end()) {
    throw InputError(fmt::format("--model: '{}' is not one of {}; or give --terms", model.model, JoinNames(published)));
  }
  if (!(alpha >= 1e-6 && alpha <= 0.5)) throw InputError(fmt::format("--alpha: {} is outside 1e-06 .. 0.5", alpha));
  settings.Check();
}

BatchDiagnosis DiagnoseBatch(const artefacts::Batch& batch, const DiagnoseOptions& options) {
  options.Check();
  stage::MeasurementSet identify = artefacts::Observations(batch, batch.identify);
  stage::MeasurementSet validate = artefacts::Observations(batch, batch.validate);
  stage::DiagnosisOptions diagnosis;
  diagnosis.alpha = options.alpha;
  diagnosis.identification = options.settings.ToOptions(identify);
  BatchDiagnosis d{stage::Diagnose(options.model.Layout(), identify, validate, diagnosis), std::move(identify),
                   std::move(validate), {}, {}};
  d.distance_errors_before_mm = DistanceErrors(d.identification, d.diagnosis.residuals_before);
  d.distance_errors_after_mm = DistanceErrors(d.identification, d.diagnosis.residuals_after);
  return d;
}

}  // namespace fvm::workflows
