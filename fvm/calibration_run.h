#pragma once
// What `calibrate` and `compare` share: choosing a model from the command line and identifying it on a batch.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "artefacts/batch_observations.h"
#include "stage/identification.h"
#include "stage/parameter_layout.h"

namespace fvm::cli {

struct IdentifySettings {
  std::string anchor = "none";  // none | first-tile
  std::string loss = "none";    // none | huber | cauchy
  double loss_scale_um = 5.0;
  std::string stitched_frame = "rotated";  // rotated | translated (stage/stitched_frame.h)

  void AddOptions(CLI::App& app);
  stage::IdentificationOptions ToOptions(const stage::MeasurementSet& set) const;
  stage::StitchedFrame Frame() const { return stage::ParseStitchedFrame(stitched_frame); }
};

// Model "9", "15", "27", "42", or a --terms spec (then the name is "terms:<spec>").
stage::ParameterLayout ModelLayout(const std::string& model, const std::string& terms);
std::string ModelName(const std::string& model, const std::string& terms);

stage::IdentificationResult IdentifyModel(const std::string& model, const std::string& terms,
                                          const stage::MeasurementSet& set, const IdentifySettings& settings);

// "id-x, id-y, id-oblique"
std::string JoinNames(const std::vector<std::string>& names);

}  // namespace fvm::cli
