#include "workflows/model_choice.h"

#include <fmt/format.h>

#include <initializer_list>
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

void IdentifySettings::Check() const {
  const auto one_of = [](const std::string& option, const std::string& value, std::initializer_list<const char*> names) {
    for (const char* n : names) {
      if (value == n) return;
    }
    throw InputError(fmt::format("{}: '{}' is not one of {}", option, value, fmt::join(names, ", ")));
  };
  one_of("--anchor", anchor, {"none", "first-tile"});
  one_of("--loss", loss, {"none", "huber", "cauchy"});
  one_of("--stitched-frame", stitched_frame, {"rotated", "translated"});
  if (!(loss_scale_um >= 1e-3 && loss_scale_um <= 1e5)) {
    throw InputError(fmt::format("--loss-scale-um: {} um is outside 0.001 .. 100000 um", loss_scale_um));
  }
  if (threads < 0) throw InputError(fmt::format("--threads: {} is negative; give 0 for all cores", threads));
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
