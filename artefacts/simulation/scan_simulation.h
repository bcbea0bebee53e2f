#pragma once
// Stitched calibration scans of a textured part on a stage with known errors (issue 21): every pixel of every tile
// shows the part where the stage really puts it, not a shifted copy of a nominal tile. A tile at encoder reading e
// sees, at its pixel offset d from the optical axis (camera frame, mm), the part point F(e) + C(e) d: the stage's
// forward model ([Pérez 2019] eq. 1) and the camera's orientation in the part frame (stage/stitched_frame.h), so the
// tiles turn with the stage's guideways as a real scan's do. The texture is a TileScene drawn once for the whole part.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "artefacts/simulation/stage_truth.h"
#include "artefacts/simulation/tile_synthesis.h"
#include "imaging/field_distortion.h"
#include "imaging/io/tile_image.h"
#include "imaging/tile_plan.h"

namespace fvm::artefacts {

// Textures as `fvm simulate scan --texture` names them: "ground" (isotropic, fills the field), "milled" (a lay:
// waves within 20 degrees of one direction, so registration is weak along the marks), "blobs" (sparse spots).
TileCameraOptions ScanTexture(const std::string& name);  // throws std::invalid_argument naming the choices

struct ScanSimulationOptions {
  int tile_px = 1024;        // square tiles
  double pixel_mm = 0.0;     // the lens' field / tile_px
  TileCameraOptions camera;  // texture, vignetting, noise
  // Height-map tiles instead of grey ones: the part's texture as heights of this standard deviation (um) on a face
  // at the scan's z, seen from each tile's focal plane (mm, float: z_part - F_z(e) - (C d)_z), with this noise.
  bool heights = false;
  double height_texture_um = 1.0, height_noise_um = 0.01;
  std::uint64_t seed = 1;
  // The objective's field distortion, the same in every tile (imaging/field_distortion.h): pixel u shows what an
  // ideal camera shows at u + d(u). Each tile is rendered on a margin and resampled (cubic) through it, its noise
  // with it. The encoder readings, the stage and the validation truth are those of the stage alone.
  imaging::FieldDistortion distortion;
  void Check() const;  // throws std::invalid_argument
};

struct SimulatedScan {
  std::string name;
  std::vector<Eigen::Vector3d> encoder_mm;  // tile centres as the encoders read them, scan order
  std::vector<imaging::TileImage> images;
};

// Renders the paths' tiles on the stage (counts as floats; 16-bit images when written).
std::vector<SimulatedScan> SimulateScans(const StageTruth& truth, const std::vector<imaging::ScanPath>& paths,
                                         const ScanSimulationOptions& options);

}  // namespace fvm::artefacts
