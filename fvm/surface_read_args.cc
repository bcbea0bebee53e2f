#include "fvm/surface_read_args.h"

#include "fvm/commands.h"

namespace fvm::cli {

void SurfaceReadArgs::AddOptions(CLI::App& app) {
  // One spelling per concept, with its unit (as --pixel-mm of fvm stitch and fvm focus); the old ones stay
  // hidden so that scripts keep working.
  app.add_option("--pixel-mm", pixel_size_mm,
                 "images: pixel size in mm (overrides the file's; required when the image does not say it)")
      ->check(Within(kPixelMm));
  AddHiddenAlias(&app, "--pixel-size,--dx-mm", pixel_size_mm, "--pixel-mm");
  app.add_option("--pixel-y-mm", pixel_size_y_mm, "images: pixel size along y in mm (default: as x)")
      ->check(Within(kPixelMm));
  AddHiddenAlias(&app, "--pixel-size-y,--dy-mm", pixel_size_y_mm, "--pixel-y-mm");
  app.add_option("--z-scale-mm", z_scale_mm,
                 "images: mm per grey level (required for integer images that do not say it)")
      ->check(Within(1e-12, 1e3, "mm"));
  AddHiddenAlias(&app, "--z-scale", z_scale_mm, "--z-scale-mm");
  app.add_option("--z-offset-mm", z_offset_mm, "images: mm added to every height (with --z-scale-mm)")->check(Within(kCoordinateMm));
  AddHiddenAlias(&app, "--z-offset", z_offset_mm, "--z-offset-mm");
  app.add_option("--invalid", invalid, "images: the raw pixel value that marks a missing point, e.g. 0")
      ->check(Within(-3.5e38, 3.5e38));  // any value a float pixel holds
  app.add_option("--unit", unit, "point clouds: the unit of the coordinates in the file")
      ->check(CLI::IsMember({"mm", "um", "m"}))
      ->default_str("mm");
}

imaging::SurfaceReadOptions SurfaceReadArgs::ToOptions() const {
  imaging::SurfaceReadOptions options;
  options.image.dx_mm = pixel_size_mm;
  options.image.dy_mm = pixel_size_y_mm;
  options.image.z_scale_mm = z_scale_mm;
  options.image.z_offset_mm = z_offset_mm;
  options.image.invalid_value = invalid;
  options.cloud.mm_per_unit = unit == "m" ? 1000.0 : unit == "um" ? 0.001 : 1.0;
  return options;
}

}  // namespace fvm::cli
