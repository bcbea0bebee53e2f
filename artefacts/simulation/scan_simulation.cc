#include "artefacts/simulation/scan_simulation.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include "stage/stitched_frame.h"

namespace fvm::artefacts {

TileCameraOptions ScanTexture(const std::string& name) {
  TileCameraOptions camera;
  camera.components = 64;
  camera.max_frequency = 0.25;
  camera.level = 20000.0;
  camera.contrast = 5000.0;
  camera.vignetting = 0.2;
  camera.noise = 0.002;               // read noise
  camera.electrons_per_count = 4.0;   // shot noise: about 70 counts at the mean level
  if (name == "ground") return camera;
  if (name == "milled") {
    camera.wave_angle_deg = 80.0;     // marks nearly along X: the waves' crests run across them
    camera.wave_spread_deg = 20.0;
    return camera;
  }
  if (name == "blobs") {
    camera.blobs = true;
    camera.level = 2000.0;
    return camera;
  }
  throw std::invalid_argument("unknown texture '" + name + "': use ground, milled or blobs");
}

void ScanSimulationOptions::Check() const {
  if (tile_px < 16) throw std::invalid_argument("scan simulation: tiles of at least 16 px");
  if (!(pixel_mm > 0.0)) throw std::invalid_argument("scan simulation: the pixel size must be positive");
  if (heights && !(height_texture_um > 0.0 && height_noise_um >= 0.0)) {
    throw std::invalid_argument("scan simulation: height texture > 0 and noise >= 0 um");
  }
  camera.Check();
  if (!distortion.Identity()) {
    distortion.Check();
    if (distortion.width_px != tile_px || distortion.height_px != tile_px) {
      throw std::invalid_argument("scan simulation: the field distortion is for other tiles than these");
    }
  }
}

std::vector<SimulatedScan> SimulateScans(const StageTruth& truth, const std::vector<imaging::ScanPath>& paths,
                                         const ScanSimulationOptions& options) {
  options.Check();
  std::mt19937_64 random(options.seed);
  TileCameraOptions camera = options.camera;
  if (options.heights) {  // the same waves, as heights in mm: no illumination, no shot noise
    camera.level = 0.0;
    camera.contrast = options.height_texture_um * 1e-3;
    camera.noise = options.height_noise_um / options.height_texture_um;
    camera.vignetting = 0.0;
    camera.electrons_per_count = 0.0;
    camera.blobs = false;
  }
  const TileScene scene(camera, random);  // one part under every path
  const double p = options.pixel_mm, half = 0.5 * options.tile_px;
  std::vector<SimulatedScan> scans;
  for (const imaging::ScanPath& path : paths) {
    SimulatedScan scan;
    scan.name = path.name;
    for (const imaging::Tile& tile : path.tiles) {
      const Eigen::Vector3d e(tile.centre_mm.x(), tile.centre_mm.y(), path.z_mm);
      // Pixel (x, y) is at d = ((x + 0.5 - half) p, -(y + 0.5 - half) p, 0) from the optical axis; the scene's
      // pixel frame has X = x_part / p, Y = -y_part / p. So the scene point of pixel (x, y) is
      // (F / p with y negated) + A (x + 0.5 - half, y + 0.5 - half), A the camera's xy block with y flipped twice.
      const Eigen::Vector3d f = truth.Forward(e);
      const Eigen::Matrix3d c = truth.Camera(e);
      Eigen::Matrix2d axes;
      axes << c(0, 0), -c(0, 1), -c(1, 0), c(1, 1);
      const Eigen::Vector2d origin = Eigen::Vector2d(f.x() / p, -f.y() / p) + axes * Eigen::Vector2d(0.5 - half, 0.5 - half);
      scan.encoder_mm.push_back(e);
      imaging::TileImage image;
      if (options.distortion.Identity()) {
        image = scene.Photograph(axes, origin, options.tile_px, options.tile_px, random);
      } else {
        const int margin = static_cast<int>(std::ceil(options.distortion.LargestDisplacementPx())) + 6;
        image = imaging::DistortTile(scene.Photograph(axes, origin - axes * Eigen::Vector2d::Constant(margin),
                                                      options.tile_px + 2 * margin, options.tile_px + 2 * margin, random),
                                     margin, options.distortion);
      }
      if (options.heights) {
        // The face lies at the scan's z; the focal plane is at F_z(e), tilted by the camera's pitch and roll.
        for (int y = 0; y < options.tile_px; ++y) {
          for (int x = 0; x < options.tile_px; ++x) {
            const double dx = (x + 0.5 - half) * p, dy = -(y + 0.5 - half) * p;
            image(y, x) += static_cast<float>(path.z_mm - f.z() - (c(2, 0) * dx + c(2, 1) * dy));
          }
        }
      }
      scan.images.push_back(std::move(image));
    }
    scans.push_back(std::move(scan));
  }
  return scans;
}

}  // namespace fvm::artefacts
