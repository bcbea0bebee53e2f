#include "workflows/model_choice.h"

#include <fmt/format.h>

#include <stdexcept>

#include "core/input_error.h"
#include "stage/fvm_stage_models.h"

namespace fvm::workflows {

std::string ModelChoice::Name() const { return terms.empty() ? model : "terms:" + terms; }

stage::ParameterLayout ModelChoice::Layout() const {
  try {
    if (!terms.empty()) return stage::ComposeLayout(terms);
    return stage::FvmModelLayout(model);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
}

stage::IdentificationOptions IdentifySettings::ToOptions(const stage::MeasurementSet& set) const {
  stage::IdentificationOptions o;
  o.anchor = anchor == "first-tile" ? stage::Anchor::kFirstTile : stage::Anchor::kNone;
  o.anchors = set.anchors;
  o.frame = Frame();
  o.loss = loss;
  o.loss_scale_mm = loss_scale_um * 1e-3;
  o.num_threads = threads;
  return o;
}

stage::IdentificationResult IdentifyModel(const ModelChoice& model, const stage::MeasurementSet& set,
                                          const IdentifySettings& settings) {
  try {
    stage::IdentificationResult result = stage::Identify(model.Layout(), set.observations, settings.ToOptions(set));
    result.calibration.model = model.Name();
    return result;
  } catch (const std::invalid_argument& e) {
    throw InputError("model " + model.Name() + ": " + e.what());
  }
}

std::string JoinNames(const std::vector<std::string>& names) { return fmt::format("{}", fmt::join(names, ", ")); }

}  // namespace fvm::workflows
