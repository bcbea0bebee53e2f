#pragma once
// Which stage model a job identifies and how: the choices every artefact job shares (calibrate, compare,
// diagnose, uncertainty), as a program or a script states them.

#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/parameter_layout.h"
#include "stage/stitched_frame.h"

namespace fvm::workflows {

// A model named as in [Pérez 2019] ("9", "15", "27", "42"), or a composed one (`terms`, e.g.
// "xTx:legendre:2,yRz:1,xWy"; then the name is "terms:<spec>").
struct ModelChoice {
  std::string model = "27";
  std::string terms;

  std::string Name() const;
  // Throws core::InputError naming the model when the name or the spec is not one.
  stage::ParameterLayout Layout() const;
};

// How stitched measurements enter the identification.
struct IdentifySettings {
  std::string anchor = "none";             // none | first-tile
  std::string loss = "none";               // none | huber | cauchy
  double loss_scale_um = 5.0;              // where the robust loss starts to bend
  std::string stitched_frame = "rotated";  // rotated | translated (stage/stitched_frame.h)
  int threads = 0;                         // 0: all cores

  stage::IdentificationOptions ToOptions(const stage::MeasurementSet& set) const;
  stage::StitchedFrame Frame() const { return stage::ParseStitchedFrame(stitched_frame); }
  // Throws core::InputError naming the option as the command line spells it (--anchor, --loss, ...).
  void Check() const;
};

// The model identified on a set; a model the data cannot carry is refused as core::InputError naming the model.
stage::IdentificationResult IdentifyModel(const ModelChoice& model, const stage::MeasurementSet& set,
                                          const IdentifySettings& settings);

// "id-x, id-y, id-oblique"
std::string JoinNames(const std::vector<std::string>& names);

}  // namespace fvm::workflows
