#include "workflows/stitch_layout.h"

#include <fmt/core.h>

#include <cmath>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/field_distortion.h"
#include "imaging/io/fiji_tile_configuration.h"
#include "imaging/io/x3p.h"

namespace fvm::workflows {

void StitchLayoutOptions::Check() const { stitch.Check(); }

namespace {

// A Fiji tile configuration's grid: the pitch the tile size and the overlap give (the first tile's header read for
// its size), else the one the positions' gaps show.
imaging::TileLayout ReadFijiLayout(const std::filesystem::path& path, double overlap) {
  const imaging::FijiTileConfiguration config = imaging::ReadFijiTileConfiguration(path);
  if (!(overlap > 0.0 && overlap < 1.0)) return imaging::FijiTileLayout(config);
  const imaging::FijiTile& first = config.tiles.front();
  Eigen::Vector2i size;
  try {
    size = imaging::ReadTileImageSize(path.parent_path() / first.file);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}:{}: tile {}: {}", config.source, first.line, first.file, e.what()));
  }
  return imaging::FijiTileLayout(config, size.cast<double>() * (1.0 - overlap));
}

}  // namespace

LayoutTiles ReadLayoutTiles(const std::filesystem::path& layout, int threads, double overlap) {
  LayoutTiles tiles;
  tiles.layout = imaging::IsFijiTileConfiguration(layout) ? ReadFijiLayout(layout, overlap)
                                                          : imaging::ReadTileLayout(layout);
  imaging::CheckLayoutForStitching(tiles.layout);
  tiles.images = imaging::ReadLayoutImages(tiles.layout, layout.parent_path(), &tiles.pixel_type, threads);
  return tiles;
}

const std::vector<Eigen::Vector2d>& StitchedLayout::PositionsPx() const {
  return field ? field->fit.positions_px : rigid.registration.positions.positions_px;
}

const std::vector<Eigen::Vector2d>& StitchedLayout::SigmaPx() const {
  return field ? field->sigma_px : rigid.registration.positions.sigma_px;
}

const StitchResult& StitchedLayout::Registered() const {
  return registered_undistorted ? *registered_undistorted : rigid;
}

int StitchPairCount(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                    const StitchOptions& options) {
  return CountGridPairs(NominalGrid(layout, static_cast<int>(images.front().cols()),
                                    static_cast<int>(images.front().rows()), options, nullptr));
}

StitchedLayout StitchLayout(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                            const StitchLayoutOptions& options, const std::function<void(int, int)>& on_pair) {
  StitchedLayout s;
  for (const auto& tile : layout.tiles) s.files.push_back(tile.file);
  s.width_px = static_cast<int>(images.front().cols());
  s.height_px = static_cast<int>(images.front().rows());
  s.options = options.stitch;
  s.rigid = StitchTiles(layout, images, options.stitch, on_pair);
  if (options.distortion) {
    try {
      StitchDistortionOptions distortion = *options.distortion;
      if (options.stitch.threads > 0) distortion.fit.threads = options.stitch.threads;  // the solve's, as the pool's
      distortion.registration = options.stitch.registration;
      s.field = StitchWithoutDistortion(s.rigid, images, distortion);
    } catch (const imaging::FieldDistortionUndeterminable& e) {
      throw InputError(fmt::format("--distortion, {}: {}", layout.source, e.what()));
    }
    if (s.field->pairs_registered_undistorted > 0) {
      StitchResult again = s.rigid;  // its grid, frame and overlap correlation
      again.registration = s.field->registration;
      DescribeRegistration(again, s.files);
      s.registered_undistorted = std::move(again);
    }
  }
  return s;
}

std::string PositionsCsv(const StitchedLayout& stitched) {
  const double pixel_mm = stitched.options.pixel_mm;
  const Eigen::Vector2d& origin = stitched.rigid.origin_mm;
  const std::vector<Eigen::Vector2d>& positions = stitched.PositionsPx();
  const std::vector<Eigen::Vector2d>& sigmas = stitched.SigmaPx();
  std::string csv = pixel_mm > 0.0 ? "file,x,y,x_mm,y_mm,registered,u_x,u_y\n" : "file,x,y,registered,u_x,u_y\n";
  for (size_t i = 0; i < stitched.files.size(); ++i) {
    const Eigen::Vector2d& p = positions[i];
    csv += fmt::format("{},{:.4f},{:.4f}", stitched.files[i], p.x(), p.y());
    if (pixel_mm > 0.0) {
      csv += fmt::format(",{:.6f},{:.6f}", origin.x() + p.x() * pixel_mm, origin.y() - p.y() * pixel_mm);
    }
    const Eigen::Vector2d& u = sigmas[i];
    csv += fmt::format(",{},{:.4f},{:.4f}\n", stitched.Registered().registration.positions.registered[i] ? 1 : 0,
                       u.x(), u.y());
  }
  return csv;
}

bool IsFijiPositionsPath(const std::filesystem::path& path) { return AsciiLower(path.extension().string()) == ".txt"; }

std::string PositionsFiji(const StitchedLayout& stitched) {
  return imaging::FormatFijiTileConfiguration(stitched.files, stitched.PositionsPx());
}

namespace {
bool IsHeightMapPath(const std::string& path) { return std::filesystem::path(path).extension() == ".x3p"; }
}  // namespace

void CheckMosaicPath(const std::string& path, double pixel_mm) {
  if (IsHeightMapPath(path) && !(pixel_mm > 0.0)) {
    throw InputError("--mosaic " + path + ": an X3P height map needs the pixel size; give --pixel-mm");
  }
}

void CheckMosaicTiles(const std::string& path, imaging::TilePixelType type) {
  if (IsHeightMapPath(path) && type != imaging::TilePixelType::kFloat) {
    throw InputError(fmt::format("--mosaic {}: the tiles hold {}-bit counts, not heights; an X3P height map needs "
                                 "float tiles in mm (or write the mosaic as .tif)",
                                 path, type == imaging::TilePixelType::kUint8 ? 8 : 16));
  }
}

imaging::Mosaic FuseStitched(const StitchedLayout& stitched, const std::vector<imaging::TileImage>& images,
                             const std::function<void(int, int)>& on_tile) {
  return imaging::FuseTiles(stitched.field ? stitched.field->undistorted : images, stitched.PositionsPx(), on_tile);
}

void WriteMosaic(const std::string& path, imaging::Mosaic mosaic, const StitchedLayout& stitched,
                 imaging::TilePixelType type) {
  if (IsHeightMapPath(path)) {
    imaging::WriteX3p(path, imaging::MosaicToHeightMap(mosaic, stitched.width_px, stitched.height_px,
                                                       stitched.options.pixel_mm, stitched.rigid.origin_mm));
    return;
  }
  // Integer pixels have no NaN: where no tile reaches is 0.
  if (type != imaging::TilePixelType::kFloat) {
    mosaic.image = mosaic.image.unaryExpr([](float v) { return std::isnan(v) ? 0.0f : v; });
  }
  imaging::WriteTileImage(path, mosaic.image, type);
}

void WriteUndistortedTiles(const std::filesystem::path& dir, const StitchedLayout& stitched,
                           const std::vector<imaging::TileImage>& images, imaging::TilePixelType type) {
  const StitchDistortionResult& field = stitched.field.value();
  const std::vector<imaging::TileImage> written =
      type == imaging::TilePixelType::kFloat ? field.undistorted : imaging::UndistortTiles(images, field.fit.field, false);
  for (size_t i = 0; i < stitched.files.size(); ++i) {
    const std::filesystem::path out = dir / stitched.files[i];
    std::filesystem::create_directories(out.parent_path());
    imaging::WriteTileImage(out, written[i], type);
  }
}

}  // namespace fvm::workflows
