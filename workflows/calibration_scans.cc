#include "workflows/calibration_scans.h"

#include <fmt/core.h>

#include <filesystem>

#include "core/input_error.h"
#include "core/progress.h"
#include "imaging/io/fiji_tile_configuration.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_registration.h"

namespace fvm::workflows {

void RefuseRepeatedFiles(const std::vector<std::string>& paths, const std::string& option) {
  // The same file under two spellings (./a.csv, a.csv, a link). Copies of one scan are caught after registration
  // (artefacts::ScanDisplacements): two layouts of the same content in two directories may be two real scans.
  std::vector<std::filesystem::path> seen;
  for (size_t i = 0; i < paths.size(); ++i) {
    std::error_code error;
    seen.push_back(std::filesystem::weakly_canonical(paths[i], error));
    if (error) seen.back() = std::filesystem::absolute(paths[i]).lexically_normal();
    for (size_t j = 0; j < i; ++j) {
      if (seen[j] == seen[i]) {
        throw InputError(fmt::format("{} {} and {} {} are the same file: a measurement counts once (given twice it "
                                     "would shrink every uncertainty by sqrt(2)); give it once",
                                     option, paths[j], option, paths[i]));
      }
    }
  }
}

std::vector<artefacts::RegisteredScan> ReadAndRegisterScans(
    const std::vector<std::string>& layouts, double pixel_mm, int threads, bool progress,
    const std::function<void(const artefacts::RegisteredScan&, const std::vector<imaging::TileImage>&)>& on_registered) {
  RefuseRepeatedFiles(layouts, "--scan");
  std::vector<artefacts::RegisteredScan> scans;
  imaging::SetImagingThreads(threads);
  for (const std::string& path : layouts) {
    if (imaging::IsFijiTileConfiguration(path)) {  // its positions are registered pixels, not the stage's readings
      throw InputError(fmt::format("{}: a Fiji tile configuration holds positions in pixels, not encoder readings; a "
                                   "calibration scan needs a CSV layout file,row,col,x,y[,z] with each tile centre's "
                                   "encoder reading in mm", path));
    }
    const imaging::TileLayout layout = imaging::ReadTileLayout(path);
    if (layout.tiles.size() < 2) {
      throw InputError(fmt::format("{}: a scan of one tile has no neighbour to register; give two or more in scan order",
                                   layout.source));
    }
    std::vector<Eigen::Vector3d> encoder_mm;
    for (const imaging::TileLayoutEntry& tile : layout.tiles) {
      if (!tile.stage_mm) {
        throw InputError(fmt::format("{}:{}: no encoder reading: a calibration scan needs the columns x,y (mm, the tile "
                                     "centre's encoder reading) and optionally z", layout.source, tile.line));
      }
      encoder_mm.emplace_back(tile.stage_mm->x(), tile.stage_mm->y(), tile.stage_z_mm.value_or(0.0));
    }
    imaging::TilePixelType type = imaging::TilePixelType::kFloat;
    const std::vector<imaging::TileImage> images =
        imaging::ReadLayoutImages(layout, std::filesystem::path(path).parent_path(), &type);
    const double field_mm = std::min(images.front().cols(), images.front().rows()) * pixel_mm;
    for (size_t k = 1; k < layout.tiles.size(); ++k) {
      const Eigen::Vector2d step = (encoder_mm[k] - encoder_mm[k - 1]).head<2>();
      if (step.cwiseAbs().maxCoeff() >= field_mm) {
        throw InputError(fmt::format(
            "{}:{}: tile {} is {:.4g}, {:.4g} mm from the one before, more than the field of {:.4g} mm ({} px of "
            "{:.4g} mm): consecutive tiles must overlap, and x, y must be encoder readings in mm (are they pixels?)",
            layout.source, layout.tiles[k].line, k + 1, step.x(), step.y(), field_mm, images.front().cols(), pixel_mm));
      }
    }
    const std::string name = std::filesystem::path(path).stem().string();
    Progress bar("registering " + name, static_cast<int>(images.size()) - 1, progress);
    // Height maps (float tiles) give the z step of every registered pair too.
    artefacts::RegisteredScan scan = artefacts::RegisterScan(name, std::move(encoder_mm), images, pixel_mm,
                                                             type == imaging::TilePixelType::kFloat, {},
                                                             [&](int, int) { bar.Advance(); });
    bar.Finish();
    if (on_registered) on_registered(scan, images);
    scans.push_back(std::move(scan));
  }
  return scans;
}

}  // namespace fvm::workflows
