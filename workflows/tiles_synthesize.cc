#include "workflows/tiles_synthesize.h"

#include <fmt/core.h>

#include <filesystem>
#include <stdexcept>

#include "artefacts/geometry/artefact.h"
#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/height_tile_synthesis.h"
#include "artefacts/simulation/sparse_tile_synthesis.h"
#include "artefacts/simulation/tile_synthesis.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "workflows/tile_set_files.h"

namespace fvm::workflows {
namespace {

// truth.csv: each tile's true top-left corner (px), the first tile at 0, 0.
std::string TruthPx(const std::vector<std::string>& files, const std::vector<Eigen::Vector2d>& truth_px) {
  std::string truth = "file,x,y\n";
  for (size_t i = 0; i < files.size(); ++i) {
    truth += fmt::format("{},{:.6f},{:.6f}\n", files[i], truth_px[i].x(), truth_px[i].y());
  }
  return truth;
}

// Height-map tiles of a known artefact (float TIFF, heights in mm, NaN where invalid), the layout with the stage
// positions the tiles were taken at, the true tile positions and the true calottes.
SynthesizedTileSet SynthesizeHeights(const TilesSynthesizeOptions& o) {
  if (o.bits != 0 && o.bits != 32) throw InputError("--bits: height tiles are float (32)");
  artefacts::HeightTileOptions options;
  options.rows = o.rows;
  options.cols = o.cols;
  options.size = o.tile_px.value_or(256);
  options.overlap = o.overlap.value_or(0.2);
  options.position_sigma_px = o.stage_sigma_px;
  options.seed = o.seed;
  artefacts::SynthesizedHeightTiles tiles;
  try {
    tiles = artefacts::SynthesizeHeightTiles(artefacts::KnownArtefact(o.artefact), options);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const std::filesystem::path dir(o.output);
  const double pixel = tiles.surface.map.dx_mm;
  SynthesizedTileSet set{"heights", o.artefact, o.output, options.size, options.size, options.overlap, pixel, {}};
  set.files = WriteTileSet(
      dir, tiles.images, tiles.tiles, tiles.nominal_centre_mm, imaging::TilePixelType::kFloat,
      fmt::format("fvm tiles synthesize --artefact {} --seed {}: {} height tiles of {} px, {} mm per px; x,y = stage "
                  "positions of the tile centres (mm). Stitch with:\nfvm stitch --layout layout.csv --overlap {:g} "
                  "--pixel-mm {} -o positions.csv --mosaic mosaic.x3p",
                  o.artefact, o.seed, tiles.images.size(), options.size, pixel, options.overlap * 100, pixel));
  std::string truth = "file,x,y,x_mm,y_mm\n";
  for (size_t i = 0; i < set.files.size(); ++i) {
    const Eigen::Vector2d error = tiles.truth_px[i] - tiles.tiles[i].nominal_px;
    truth += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f}\n", set.files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y(),
                         tiles.nominal_centre_mm[i].x() + error.x() * pixel,
                         tiles.nominal_centre_mm[i].y() - error.y() * pixel);
  }
  artefacts::CentreExport calottes;
  calottes.comments.push_back(
      fmt::format("fvm tiles synthesize --artefact {} --seed {}: the true calottes (mm)", o.artefact, o.seed));
  for (const auto& c : tiles.surface.truth) {
    artefacts::CentreRecord record;
    record.id = c.id;
    record.position = c.centre;
    record.radius_mm = c.radius_mm;
    calottes.centres.push_back(record);
  }
  artefacts::WriteCentreExport(dir / "calottes.csv", calottes);
  WriteFileAtomically(dir / "truth.csv", truth);
  return set;
}

// What a real microscope set of a sparse sample looks like: 16-bit blobs on a smooth background, thin overlaps, a
// stage with a systematic step error and a drift.
SynthesizedTileSet SynthesizeSparse(const TilesSynthesizeOptions& o) {
  if (o.bits != 0 && o.bits != 16) throw InputError("--bits: sparse tiles are 16-bit counts");
  artefacts::SparseTileOptions options;
  if (o.rows > 0) options.rows = o.rows;
  if (o.cols > 0) options.cols = o.cols;
  if (o.tile_px) options.width = options.height = *o.tile_px;
  if (o.overlap) options.overlap = *o.overlap;
  options.repeatability_px = o.stage_sigma_px;
  options.seed = o.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize --texture sparse: ") + e.what());
  }
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeSparseTiles(options);
  SynthesizedTileSet set{"sparse", "", o.output, options.width, options.height, options.overlap, 0.0, {}};
  set.files = WriteTileSet(
      o.output, tiles.images, tiles.tiles, {}, imaging::TilePixelType::kUint16,
      fmt::format("fvm tiles synthesize --texture sparse --seed {}: {} x {} tiles of {} x {} px, overlap {}; the "
                  "stage steps {:+g}, {:+g} px per column and {:+g}, {:+g} px per row off the nominal, "
                  "repeatability {} px",
                  o.seed, options.rows, options.cols, options.width, options.height, options.overlap,
                  options.east_step_error_px.x(), options.east_step_error_px.y(), options.south_step_error_px.x(),
                  options.south_step_error_px.y(), options.repeatability_px));
  WriteFileAtomically(std::filesystem::path(o.output) / "truth.csv", TruthPx(set.files, tiles.truth_px));
  return set;
}

SynthesizedTileSet SynthesizeWaves(const TilesSynthesizeOptions& o) {
  if (o.texture != "waves") throw InputError("--texture " + o.texture + ": give waves or sparse");
  artefacts::TileSynthesisOptions options;
  options.rows = o.rows > 0 ? o.rows : 3;
  options.cols = o.cols > 0 ? o.cols : 3;
  options.width = options.height = o.tile_px.value_or(256);
  options.overlap = o.overlap.value_or(0.2);
  options.position_sigma_px = o.stage_sigma_px;
  options.seed = o.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const int bits = o.bits == 0 ? 16 : o.bits;
  if (bits != 8 && bits != 16 && bits != 32) throw InputError("--bits: 8, 16 or 32 (float)");
  if (bits == 8) options.camera.level = 120.0, options.camera.contrast = 25.0;  // 0..255 with the vignetting
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(options);
  SynthesizedTileSet set{"waves", "", o.output, options.width, options.height, options.overlap, 0.0, {}};
  set.files = WriteTileSet(o.output, tiles.images, tiles.tiles, {},
                           bits == 8    ? imaging::TilePixelType::kUint8
                           : bits == 16 ? imaging::TilePixelType::kUint16
                                        : imaging::TilePixelType::kFloat,
                           fmt::format("fvm tiles synthesize --seed {}: {} x {} tiles of {} px, overlap {}", o.seed,
                                       options.rows, options.cols, options.width, options.overlap));
  WriteFileAtomically(std::filesystem::path(o.output) / "truth.csv", TruthPx(set.files, tiles.truth_px));
  return set;
}

}  // namespace

SynthesizedTileSet SynthesizeTileSet(const TilesSynthesizeOptions& options) {
  if (options.output.empty()) throw InputError("-o: give the directory for the tiles");
  if (!options.artefact.empty() && options.texture != "waves") {
    throw InputError("--texture " + options.texture + " and --artefact: give one of them");
  }
  if (!options.artefact.empty()) return SynthesizeHeights(options);
  if (options.texture == "sparse") return SynthesizeSparse(options);
  return SynthesizeWaves(options);
}

Summary Summarize(const SynthesizedTileSet& set) {
  nlohmann::ordered_json json = {{"kind", set.kind},         {"tiles", set.files.size()},
                                 {"width_px", set.width_px}, {"height_px", set.height_px},
                                 {"overlap", set.overlap}};
  std::string text;
  if (set.kind == "heights") {
    json["pixel_mm"] = set.pixel_mm;
    json["artefact"] = set.artefact;
    text = fmt::format("{} height tiles of {} ({} x {} px, {} mm per px), layout.csv, truth.csv (true positions) and "
                       "calottes.csv (true calottes) written to {}\n",
                       set.files.size(), set.artefact, set.width_px, set.height_px, set.pixel_mm, set.output);
  } else if (set.kind == "sparse") {
    text = fmt::format("{} sparse tiles of {} x {} px (overlap {:g} %), layout.csv and truth.csv (true positions, px) "
                       "written to {}\n",
                       set.files.size(), set.width_px, set.height_px, set.overlap * 100, set.output);
  } else {
    text = fmt::format("{} tiles, layout.csv and truth.csv (true positions, px) written to {}\n", set.files.size(),
                       set.output);
  }
  return {json, text, std::nullopt};
}

}  // namespace fvm::workflows
