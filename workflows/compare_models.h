#pragma once
// Every model order side by side on a batch, judged on held-out placements, and which one to trust (`fvm compare`).

#include <functional>
#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "stage/validation.h"
#include "workflows/model_choice.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// What `fvm compare` takes besides the batch, with its defaults.
struct CompareOptions {
  std::vector<std::string> models = stage::FvmModelNames();  // the published models
  IdentifySettings settings;
  // Throws InputError naming the option as the command line spells it (--models, --anchor, ...).
  void Check() const;
};

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
ModelComparison CompareModels(const artefacts::Batch& batch, const CompareOptions& options,
                              const std::function<void(const std::string& model)>& on_model = {});

// The --json document (without the batch's path, the front end's to add), the printed table (naming `batch_name`)
// and no report.
Summary Summarize(const ModelComparison& comparison, const CompareOptions& options, const std::string& batch_name);

}  // namespace fvm::workflows
