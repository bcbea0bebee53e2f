#pragma once
// Every model order side by side on a batch, judged on held-out placements, and which one to trust (`fvm compare`).

#include <functional>
#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "stage/identification.h"
#include "stage/validation.h"
#include "workflows/model_choice.h"

namespace fvm::workflows {

struct ModelScore {
  std::string model;
  int nominal = 0;  // parameters of the model as published
  stage::IdentificationResult identification;
  stage::ValidationStats validation;       // first-tile figure
  stage::FrameFreeStats rigid, distances;  // what no frame changes
  std::vector<double> distance_errors;     // mm, from the first centre of each held-out placement
  double distance_error_rms_mm = 0.0;
  double aic = 0, bic = 0;                 // of the identification residuals
};

struct ModelComparison {
  std::vector<ModelScore> scores;  // in the order asked
  bool validation_placements = false;  // judged on the batch's validation placements, else each left out in turn
  std::string recommendation;      // which model to use and why, for people
};

// `models`: names of the published models ("9", "15", "27", "42"). The held-out placements are the batch's
// validation ones, else each identification placement left out in turn. `on_model` is told each model before it
// is identified (progress).
ModelComparison CompareModels(const artefacts::Batch& batch, const std::vector<std::string>& models,
                              const IdentifySettings& settings,
                              const std::function<void(const std::string& model)>& on_model = {});

}  // namespace fvm::workflows
