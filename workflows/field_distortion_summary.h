#pragma once
// What a job says about the field distortion it took out of its tiles (`fvm stitch --distortion`, `fvm calibrate
// --scan --distortion`): the field's document (workflows/field_distortion_file.h) with the fit's figures, and the
// printed lines (its largest displacement, the terms with their standard uncertainties, the fixed linear part).

#include <nlohmann/json.hpp>
#include <string>

#include "imaging/field_distortion_fit.h"

namespace fvm::workflows {

// `identified`: false for a field read from a file (positions only). `pixel_mm` > 0 adds micrometres.
nlohmann::ordered_json FieldDistortionFitJson(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);
std::string FieldDistortionFitText(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);

}  // namespace fvm::workflows
