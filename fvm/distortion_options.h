#pragma once
// The command-line face of the field-distortion options `fvm stitch` and `fvm calibrate --scan` share
// (workflows/distortion_options.h): --distortion [ORDER], --distortion-file F, --save-distortion F (and
// --undistorted DIR for stitch) bound into the workflow's struct.

#include <CLI/CLI.hpp>

#include "workflows/distortion_options.h"

namespace fvm::cli {

// The workflow's options and the --distortion option, whose count says whether it was given (it takes an
// optional ORDER).
struct DistortionArgs : workflows::DistortionOptions {
  CLI::Option* order_option = nullptr;
  // The options as parsed: `identify` set when --distortion was given.
  workflows::DistortionOptions Parsed() const {
    workflows::DistortionOptions parsed = *this;
    parsed.identify = order_option != nullptr && order_option->count() > 0;
    return parsed;
  }
  bool Requested() const { return Parsed().Requested(); }
  void Check() const { Parsed().Check(); }
};

void AddDistortionOptions(CLI::App* sub, DistortionArgs* args, bool undistorted_dir);

using workflows::DistortionJson;
using workflows::DistortionText;

}  // namespace fvm::cli
