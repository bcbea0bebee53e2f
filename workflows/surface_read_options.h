#pragma once
// How to read a surface or cloud file, as `fvm info` and `fvm fit` spell it (--pixel-mm, --z-scale-mm, --unit, ...):
// what an image does not tell about its pixels and heights, and the unit of a point cloud.

#include <optional>
#include <string>

#include "core/input_error.h"
#include "imaging/io/surface_file.h"

namespace fvm::workflows {

struct SurfaceReadOptions {
  double pixel_mm = 0.0;      // images: pixel size (overrides the file's)
  double pixel_y_mm = 0.0;    // images: pixel size along y (0: as x)
  double z_scale_mm = 0.0;    // images: mm per grey level
  double z_offset_mm = 0.0;   // images: mm added to every height
  std::optional<double> invalid;  // images: the raw value that marks a missing point
  std::string unit = "mm";    // point clouds: mm, um or m

  // The readers' options; throws InputError naming --unit for another unit.
  imaging::SurfaceReadOptions ToOptions() const {
    if (unit != "mm" && unit != "um" && unit != "m") throw InputError("--unit '" + unit + "': use mm, um or m");
    imaging::SurfaceReadOptions options;
    options.image.dx_mm = pixel_mm;
    options.image.dy_mm = pixel_y_mm;
    options.image.z_scale_mm = z_scale_mm;
    options.image.z_offset_mm = z_offset_mm;
    options.image.invalid_value = invalid;
    options.cloud.mm_per_unit = unit == "m" ? 1000.0 : unit == "um" ? 0.001 : 1.0;
    return options;
  }
};

}  // namespace fvm::workflows
