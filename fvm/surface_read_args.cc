#include "fvm/surface_read_args.h"

#include "fvm/commands.h"

namespace fvm::cli {

void AddSurfaceReadOptions(CLI::App& app, workflows::SurfaceReadOptions& read) {
  // One spelling per concept, with its unit (as --pixel-mm of fvm stitch and fvm focus); the old ones stay
  // hidden so that scripts keep working.
  app.add_option("--pixel-mm", read.pixel_mm,
                 "images: pixel size in mm (overrides the file's; required when the image does not say it)")
      ->check(Within(kPixelMm));
  AddHiddenAlias(&app, "--pixel-size,--dx-mm", read.pixel_mm, "--pixel-mm");
  app.add_option("--pixel-y-mm", read.pixel_y_mm, "images: pixel size along y in mm (default: as x)")
      ->check(Within(kPixelMm));
  AddHiddenAlias(&app, "--pixel-size-y,--dy-mm", read.pixel_y_mm, "--pixel-y-mm");
  app.add_option("--z-scale-mm", read.z_scale_mm,
                 "images: mm per grey level (required for integer images that do not say it)")
      ->check(Within(1e-12, 1e3, "mm"));
  AddHiddenAlias(&app, "--z-scale", read.z_scale_mm, "--z-scale-mm");
  app.add_option("--z-offset-mm", read.z_offset_mm, "images: mm added to every height (with --z-scale-mm)")->check(Within(kCoordinateMm));
  AddHiddenAlias(&app, "--z-offset", read.z_offset_mm, "--z-offset-mm");
  app.add_option("--invalid", read.invalid, "images: the raw pixel value that marks a missing point, e.g. 0")
      ->check(Within(-3.5e38, 3.5e38));  // any value a float pixel holds
  app.add_option("--unit", read.unit, "point clouds: the unit of the coordinates in the file")
      ->check(CLI::IsMember({"mm", "um", "m"}))
      ->default_str("mm");
}

}  // namespace fvm::cli
