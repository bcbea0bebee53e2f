#pragma once
// The field-distortion options `fvm stitch` and `fvm calibrate --scan` share: --distortion [ORDER],
// --distortion-file F, --save-distortion F (and --undistorted DIR for stitch), bound, checked, and the field's
// text and JSON.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "imaging/field_distortion.h"
#include "imaging/field_distortion_fit.h"

namespace fvm::cli {

struct DistortionArgs {
  CLI::Option* order_option = nullptr;
  std::string order;  // as given; empty or a flag's "true": the default order
  std::string file;   // --distortion-file
  std::string save;   // --save-distortion
  std::string undistorted_dir;  // --undistorted (stitch only)
  bool Requested() const { return (order_option && order_option->count() > 0) || !file.empty(); }
  // The order to identify (0 with --distortion-file). Throws InputError naming the option.
  int Order() const;
  // The saved field, when --distortion-file gives one (InputError naming the file).
  std::optional<imaging::FieldDistortion> Known() const;
  void Check() const;  // conflicting or orphaned options: InputError naming them
};

void AddDistortionOptions(CLI::App* sub, DistortionArgs* args, bool undistorted_dir);

// What is printed about a field: its largest displacement, terms with u, the fixed linear part.
std::string DistortionText(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);
// The field's document (workflows::FieldDistortionJson) with the fit's figures.
nlohmann::ordered_json DistortionJson(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm);

}  // namespace fvm::cli
