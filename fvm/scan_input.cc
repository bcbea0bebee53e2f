#include "fvm/scan_input.h"

#include <fmt/core.h>

#include <filesystem>

#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_registration.h"

namespace fvm::cli {

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

std::vector<artefacts::RegisteredScan> ReadAndRegisterScans(const std::vector<std::string>& layouts, double pixel_mm) {
  RefuseRepeatedFiles(layouts, "--scan");
  std::vector<artefacts::RegisteredScan> scans;
  imaging::SetImagingThreads(ThreadCount());
  for (const std::string& path : layouts) {
    const imaging::TileLayout layout = imaging::ReadTileLayout(path);
    if (layout.tiles.size() < 2) {
      throw InputError(fmt::format("{}: a scan of one tile has no neighbour to register; give two or more in scan order",
                                   layout.source));
    }
    artefacts::RegisteredScan scan;
    scan.name = std::filesystem::path(path).stem().string();
    for (const imaging::TileLayoutEntry& tile : layout.tiles) {
      if (!tile.stage_mm) {
        throw InputError(fmt::format("{}:{}: no encoder reading: a calibration scan needs the columns x,y (mm, the tile "
                                     "centre's encoder reading) and optionally z", layout.source, tile.line));
      }
      scan.encoder_mm.emplace_back(tile.stage_mm->x(), tile.stage_mm->y(), tile.stage_z_mm.value_or(0.0));
    }
    imaging::TilePixelType type = imaging::TilePixelType::kFloat;
    const std::vector<imaging::TileImage> images =
        imaging::ReadLayoutImages(layout, std::filesystem::path(path).parent_path(), &type);
    const double field_mm = std::min(images.front().cols(), images.front().rows()) * pixel_mm;
    std::vector<Eigen::Vector2d> nominal;
    for (size_t k = 0; k < layout.tiles.size(); ++k) {
      const Eigen::Vector3d& e = scan.encoder_mm[k];
      if (k > 0) {
        const Eigen::Vector2d step = (e - scan.encoder_mm[k - 1]).head<2>();
        if (step.cwiseAbs().maxCoeff() >= field_mm) {
          throw InputError(fmt::format(
              "{}:{}: tile {} is {:.4g}, {:.4g} mm from the one before, more than the field of {:.4g} mm ({} px of "
              "{:.4g} mm): consecutive tiles must overlap, and x, y must be encoder readings in mm (are they pixels?)",
              layout.source, layout.tiles[k].line, k + 1, step.x(), step.y(), field_mm, images.front().cols(), pixel_mm));
        }
      }
      nominal.push_back(Eigen::Vector2d(e.x() - scan.encoder_mm[0].x(), scan.encoder_mm[0].y() - e.y()) / pixel_mm);
    }
    Progress progress("registering " + scan.name, static_cast<int>(images.size()) - 1, ShowProgress());
    scan.registration = imaging::RegisterTileChain(images, nominal, {}, [&](int, int) { progress.Advance(); });
    progress.Finish();
    if (type == imaging::TilePixelType::kFloat) {  // height maps: the z step of every registered pair too
      for (const imaging::PairRegistration& pair : scan.registration.pairs) {
        scan.height_steps.push_back(pair.accepted ? imaging::OverlapHeightStep(images[static_cast<size_t>(pair.a)],
                                                                               images[static_cast<size_t>(pair.b)], pair.offset_px)
                                                  : imaging::HeightStep{});
      }
    }
    scans.push_back(std::move(scan));
  }
  return scans;
}

}  // namespace fvm::cli
