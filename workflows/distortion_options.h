#pragma once
// The field-distortion options `fvm stitch` and `fvm calibrate --scan` share (--distortion [ORDER],
// --distortion-file F, --save-distortion F, and --undistorted DIR for stitch) with their checks, and the field's
// printed text and JSON block. The command line binds its options into these fields (fvm/distortion_options.h);
// Python takes them as keywords.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"

namespace fvm::workflows {

struct DistortionOptions {
  bool identify = false;        // --distortion given: identify a field from the overlaps
  std::string order;            // its ORDER as given; empty or a flag's "true": the default order
  std::string file;             // --distortion-file: a saved field, positions only
  std::string save;             // --save-distortion
  std::string undistorted_dir;  // --undistorted (stitch only)

  bool Requested() const { return identify || !file.empty(); }
  // The order to identify (0 with --distortion-file). Throws InputError naming the option.
  int Order() const;
  // The saved field, when --distortion-file gives one (InputError naming the file).
  std::optional<imaging::FieldDistortion> Known() const;
  void Check() const;  // conflicting or orphaned options: InputError naming them
};

// What is printed about a field: its largest displacement, terms with u, the fixed linear part.
std::string DistortionText(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);
// The field's document (workflows::FieldDistortionJson) with the fit's figures.
nlohmann::ordered_json DistortionJson(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);

}  // namespace fvm::workflows
