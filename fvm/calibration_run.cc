#include "fvm/calibration_run.h"

#include "core/input_error.h"
#include "fvm/commands.h"
#include "stage/fvm_stage_models.h"

namespace fvm::cli {

void IdentifySettings::AddOptions(CLI::App& app) {
  app.add_option("--anchor", anchor,
                 "how stitched measurements are referenced: 'none' ([Pérez 2019] procedure: every placement starts at "
                 "one spot) or 'first-tile' (each placement anchored at the stage error of its own first tile)")
      ->check(CLI::IsMember({"none", "first-tile"}))
      ->capture_default_str();
  app.add_option("--stitched-frame", stitched_frame,
                 "how each stitched export sits in the stage frame: 'rotated' (the instrument registers tiles by "
                 "translation, so the mosaic keeps the orientation of its first tile, turned with the stage there; "
                 "first-tile figures turn it by the model's rotation terms, or, for a model without rotation terms of "
                 "order 1 or more, carry the turn's spread in their prediction) or 'translated' (the turn left out)")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  app.add_option("--loss", loss, "robust loss on each centre's Euclidean error")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}))
      ->capture_default_str();
  app.add_option("--loss-scale-um", loss_scale_um, "error (um) where the robust loss starts to bend")
      ->check(Within(1e-3, 1e5, "um"))
      ->capture_default_str();
}

stage::IdentificationOptions IdentifySettings::ToOptions(const stage::MeasurementSet& set) const {
  stage::IdentificationOptions o;
  o.anchor = anchor == "first-tile" ? stage::Anchor::kFirstTile : stage::Anchor::kNone;
  o.anchors = set.anchors;
  o.frame = Frame();
  o.loss = loss;
  o.loss_scale_mm = loss_scale_um * 1e-3;
  o.num_threads = ThreadCount();
  return o;
}

stage::ParameterLayout ModelLayout(const std::string& model, const std::string& terms) {
  try {
    if (!terms.empty()) return stage::ComposeLayout(terms);
    return stage::FvmModelLayout(model);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
}

std::string ModelName(const std::string& model, const std::string& terms) {
  return terms.empty() ? model : "terms:" + terms;
}

stage::IdentificationResult IdentifyModel(const std::string& model, const std::string& terms,
                                          const stage::MeasurementSet& set, const IdentifySettings& settings) {
  try {
    stage::IdentificationResult result = stage::Identify(ModelLayout(model, terms), set.observations, settings.ToOptions(set));
    result.calibration.model = ModelName(model, terms);
    return result;
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("model ") + ModelName(model, terms) + ": " + e.what());
  }
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace fvm::cli
