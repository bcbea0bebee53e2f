#pragma once
// The command-line options that say how to read a surface or cloud file (fvm info, fvm fit, ...): what an image
// does not tell about its pixels and heights, and the unit of a point cloud.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "imaging/io/surface_file.h"

namespace fvm::cli {

struct SurfaceReadArgs {
  double pixel_size_mm = 0.0;
  double pixel_size_y_mm = 0.0;
  double z_scale_mm = 0.0;
  double z_offset_mm = 0.0;
  std::optional<double> invalid;
  std::string unit = "mm";

  void AddOptions(CLI::App& app);
  imaging::SurfaceReadOptions ToOptions() const;
};

}  // namespace fvm::cli
