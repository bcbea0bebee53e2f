#pragma once
// A field distortion kept for later scans with the same objective (`fvm stitch --save-distortion F`, read back by
// `--distortion-file F`), and the same document in the commands' --json:
//   {"format": "fvm-field-distortion", "version": 1, "width_px", "height_px", "order",
//    "terms": [{"name", "value_px", "u_px"}], "covariance_px2": [[...]], "fixed": "<kFixedLinearPart>",
//    "largest_displacement_px", "largest_displacement_um" (when the pixel size is known), "sigma_px"}

#include <nlohmann/json.hpp>
#include <string>

#include "imaging/field_distortion.h"

namespace fvm::workflows {

// `pixel_mm` > 0 adds the largest displacement in um.
nlohmann::ordered_json FieldDistortionJson(const imaging::FieldDistortion& field, double pixel_mm = 0.0);
// Writes atomically; throws InputError naming the file.
void WriteFieldDistortion(const std::string& path, const imaging::FieldDistortion& field, double pixel_mm = 0.0);
// Throws InputError naming the file and what is wrong (not JSON, another format, terms that do not match the order).
imaging::FieldDistortion ReadFieldDistortion(const std::string& path);

}  // namespace fvm::workflows
