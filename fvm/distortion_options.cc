// The field-distortion options of fvm stitch and fvm calibrate --scan, bound.

#include "fvm/distortion_options.h"

namespace fvm::cli {

void AddDistortionOptions(CLI::App* sub, DistortionArgs* args, bool undistorted_dir) {
  args->order_option =
      sub->add_option("--distortion", args->order,
                      "identify the objective's field distortion from the overlaps, jointly with the positions: "
                      "radial (k1, k2), tangential (p1, p2) and polynomial terms up to ORDER (2-6, default 3) in the "
                      "tile's pixel coordinates; its linear part (scale, shear, turn) cannot be told from the stage "
                      "steps and stays fixed at 0. Refuses what the overlaps cannot determine (a strip in one "
                      "direction, texture-free overlaps, too high an order), naming the terms")
          ->expected(0, 1);
  sub->add_option("--distortion-file", args->file,
                  "take the field saved by --save-distortion (the same objective): positions only");
  sub->add_option("--save-distortion", args->save, "write the field (JSON: terms with u, covariance) for later scans");
  if (undistorted_dir) {
    sub->add_option("--undistorted", args->undistorted_dir,
                    "write each tile resampled without the field into this directory: same name, size and pixel "
                    "type (float tiles: NaN where the raw tile does not reach; integer tiles: the nearest edge pixel)");
  }
}

}  // namespace fvm::cli
