#pragma once
// The discrepancy workflow on a batch (`fvm diagnose`): which physical effect the stage model misses, added step
// by step while held-out placements confirm it (stage/discrepancy.h).

#include <string>
#include <vector>

#include "artefacts/io/batch.h"
#include "stage/discrepancy.h"
#include "workflows/model_choice.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct DiagnoseOptions {
  ModelChoice model;
  // Translated: the plainest convention, so that a turn of the stitched frame is found and named (frame_rotation).
  IdentifySettings settings{.stitched_frame = "translated"};
  double alpha = 0.01;  // significance of an effect's F test
  // Throws InputError naming the option as the command line spells it (--model, --terms, --alpha, ...).
  void Check() const;
};

struct BatchDiagnosis {
  stage::Diagnosis diagnosis;
  stage::MeasurementSet identification, validation;
  // The first-order change of each distance from a placement's first centre to the others (mm), from the
  // identification residuals before and after the effects accepted; `after` is empty when outliers were taken out
  // (the residuals then belong to fewer centres).
  std::vector<double> distance_errors_before_mm, distance_errors_after_mm;
};

BatchDiagnosis DiagnoseBatch(const artefacts::Batch& batch, const DiagnoseOptions& options);

// The --json document (without the batch's path, the front end's to add), the printed text and the report's data
// (residual maps before and after, the steps), naming `batch_name` where the command names its batch.
Summary Summarize(const BatchDiagnosis& diagnosis, const DiagnoseOptions& options, const std::string& batch_name);

}  // namespace fvm::workflows
