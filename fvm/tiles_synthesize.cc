// fvm tiles synthesize: tile sets with a known truth for fvm stitch (textured, height maps of an artefact, or a
// sparse sample on a drifting stage).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <memory>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "core/file_io.h"
#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/height_tile_synthesis.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "artefacts/simulation/rendered_stitching_strategy.h"
#include "artefacts/simulation/stitching_strategy.h"
#include "artefacts/simulation/sparse_tile_synthesis.h"
#include "artefacts/simulation/tile_synthesis.h"
#include "stage/io/calibration_file.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "fvm/tile_set_files.h"
#include "imaging/io/tile_image.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_plan.h"
#include "imaging/tile_registration.h"

namespace fvm::cli {
namespace {

struct SynthArgs {
  std::string output;
  int rows = 0, cols = 0, size = 256;  // 0: 3, or with --artefact as many as cover it
  std::string overlap = "0.2";
  double sigma_px = 1.5;
  int bits = 0;  // 0: 16, or with --artefact 32
  std::string artefact;
  std::string texture = "waves";
  bool size_given = false, overlap_given = false;
  std::uint64_t seed = 1;
};

// Height-map tiles of a known artefact (float TIFF, heights in mm, NaN where invalid), the layout with the stage
// positions the tiles were taken at, the true tile positions and the true calottes.
void RunSynthesizeHeights(const SynthArgs& args) {
  if (args.bits != 0 && args.bits != 32) throw InputError("--bits: height tiles are float (32)");
  artefacts::HeightTileOptions options;
  options.rows = args.rows;
  options.cols = args.cols;
  options.size = args.size;
  options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.position_sigma_px = args.sigma_px;
  options.seed = args.seed;
  artefacts::SynthesizedHeightTiles tiles;
  try {
    tiles = artefacts::SynthesizeHeightTiles(artefacts::KnownArtefact(args.artefact), options);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const std::filesystem::path dir(args.output);
  const double pixel = tiles.surface.map.dx_mm;
  const std::vector<std::string> files = WriteTileSet(
      dir, tiles.images, tiles.tiles, tiles.nominal_centre_mm, imaging::TilePixelType::kFloat,
      fmt::format("fvm tiles synthesize --artefact {} --seed {}: {} height tiles of {} px, {} mm per px; x,y = stage "
                  "positions of the tile centres (mm). Stitch with:\nfvm stitch --layout layout.csv --overlap {:g} "
                  "--pixel-mm {} -o positions.csv --mosaic mosaic.x3p",
                  args.artefact, args.seed, tiles.images.size(), args.size, pixel, options.overlap * 100, pixel));
  std::string truth = "file,x,y,x_mm,y_mm\n";
  for (size_t i = 0; i < files.size(); ++i) {
    const Eigen::Vector2d error = tiles.truth_px[i] - tiles.tiles[i].nominal_px;
    truth += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y(),
                         tiles.nominal_centre_mm[i].x() + error.x() * pixel,
                         tiles.nominal_centre_mm[i].y() - error.y() * pixel);
  }
  artefacts::CentreExport calottes;
  calottes.comments.push_back(fmt::format("fvm tiles synthesize --artefact {} --seed {}: the true calottes (mm)",
                                          args.artefact, args.seed));
  for (const auto& c : tiles.surface.truth) {
    artefacts::CentreRecord record;
    record.id = c.id;
    record.position = c.centre;
    record.radius_mm = c.radius_mm;
    calottes.centres.push_back(record);
  }
  artefacts::WriteCentreExport(dir / "calottes.csv", calottes);
  WriteFileAtomically(dir / "truth.csv", truth);
  fmt::print("{} height tiles of {} ({} x {} px, {} mm per px), layout.csv, truth.csv (true positions) and "
             "calottes.csv (true calottes) written to {}\n",
             tiles.images.size(), args.artefact, args.size, args.size, pixel, args.output);
}

// What a real microscope set of a sparse sample looks like (artefacts/simulation/sparse_tile_synthesis.h): 16-bit
// blobs on a smooth background, thin overlaps, a stage with a systematic step error and a drift.
void RunSynthesizeSparse(const SynthArgs& args) {
  if (args.bits != 0 && args.bits != 16) throw InputError("--bits: sparse tiles are 16-bit counts");
  artefacts::SparseTileOptions options;
  if (args.rows > 0) options.rows = args.rows;
  if (args.cols > 0) options.cols = args.cols;
  if (args.size_given) options.width = options.height = args.size;
  if (args.overlap_given) options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.repeatability_px = args.sigma_px;
  options.seed = args.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize --texture sparse: ") + e.what());
  }
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeSparseTiles(options);
  const std::vector<std::string> files = WriteTileSet(
      args.output, tiles.images, tiles.tiles, {}, imaging::TilePixelType::kUint16,
      fmt::format("fvm tiles synthesize --texture sparse --seed {}: {} x {} tiles of {} x {} px, overlap {}; the "
                  "stage steps {:+g}, {:+g} px per column and {:+g}, {:+g} px per row off the nominal, "
                  "repeatability {} px",
                  args.seed, options.rows, options.cols, options.width, options.height, options.overlap,
                  options.east_step_error_px.x(), options.east_step_error_px.y(), options.south_step_error_px.x(),
                  options.south_step_error_px.y(), options.repeatability_px));
  std::string truth = "file,x,y\n";
  for (size_t i = 0; i < files.size(); ++i) {
    truth += fmt::format("{},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y());
  }
  WriteFileAtomically(std::filesystem::path(args.output) / "truth.csv", truth);
  fmt::print("{} sparse tiles of {} x {} px (overlap {:g} %), layout.csv and truth.csv (true positions, px) written "
             "to {}\n",
             tiles.images.size(), options.width, options.height, options.overlap * 100, args.output);
}

void RunSynthesize(const SynthArgs& args) {
  if (!args.artefact.empty() && args.texture != "waves") {
    throw InputError("--texture " + args.texture + " and --artefact: give one of them");
  }
  if (!args.artefact.empty()) return RunSynthesizeHeights(args);
  if (args.texture == "sparse") return RunSynthesizeSparse(args);
  if (args.texture != "waves") throw InputError("--texture " + args.texture + ": give waves or sparse");
  artefacts::TileSynthesisOptions options;
  options.rows = args.rows > 0 ? args.rows : 3;
  options.cols = args.cols > 0 ? args.cols : 3;
  options.width = options.height = args.size;
  options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  options.position_sigma_px = args.sigma_px;
  options.seed = args.seed;
  try {
    options.Check();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles synthesize: ") + e.what());
  }
  const int bits = args.bits == 0 ? 16 : args.bits;
  if (bits != 8 && bits != 16 && bits != 32) throw InputError("--bits: 8, 16 or 32 (float)");
  if (bits == 8) options.camera.level = 120.0, options.camera.contrast = 25.0;  // 0..255 with the vignetting
  const artefacts::SynthesizedTiles tiles = artefacts::SynthesizeTiles(options);
  const std::vector<std::string> files = WriteTileSet(
      args.output, tiles.images, tiles.tiles, {},
      bits == 8    ? imaging::TilePixelType::kUint8
      : bits == 16 ? imaging::TilePixelType::kUint16
                   : imaging::TilePixelType::kFloat,
      fmt::format("fvm tiles synthesize --seed {}: {} x {} tiles of {} px, overlap {}", args.seed, options.rows,
                  options.cols, args.size, options.overlap));
  std::string truth = "file,x,y\n";
  for (size_t i = 0; i < files.size(); ++i) {
    truth += fmt::format("{},{:.6f},{:.6f}\n", files[i], tiles.truth_px[i].x(), tiles.truth_px[i].y());
  }
  WriteFileAtomically(std::filesystem::path(args.output) / "truth.csv", truth);
  fmt::print("{} tiles, layout.csv and truth.csv (true positions, px) written to {}\n", tiles.images.size(),
             args.output);
}

}  // namespace

void AddTilesSynthesize(CLI::App* tiles) {
  auto synth_args = std::make_shared<SynthArgs>();
  CLI::App* synth = tiles->add_subcommand(
      "synthesize", "synthetic overlapping tiles with known positions, for trying fvm stitch");
  synth->add_option("-o,--output", synth_args->output, "directory for the tiles, layout.csv and truth.csv")
      ->required();
  synth->add_option("--rows", synth_args->rows, "tile rows (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--cols", synth_args->cols, "tile columns (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--tile-px", synth_args->size, "tile width and height (px; --texture sparse: 245 x 183)")
      ->check(Count(16, 8192))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->size_given = true; });
  AddHiddenAlias(synth, "--size", synth_args->size, "--tile-px")->each([synth_args](const std::string&) {
    synth_args->size_given = true;
  });
  synth->add_option("--overlap", synth_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %; --texture sparse: 6)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->overlap_given = true; });
  synth->add_option("--stage-sigma-px", synth_args->sigma_px,
                    "standard deviation of the stage error per axis (px; with --texture sparse the repeatability "
                    "on top of the systematic step error)")
      ->check(Within(0.0, 1e3, "px"))
      ->capture_default_str();
  synth->add_option("--texture", synth_args->texture,
                    "waves: a dense random texture; sparse: 16-bit blobs on a smooth background with shot noise, "
                    "5 x 5 tiles, a stage that steps 1.2 px long and drifts 4 px per column (like a real "
                    "microscope set of a sparse sample)")
      ->capture_default_str();
  AddHiddenAlias(synth, "--stage-error", synth_args->sigma_px, "--stage-sigma-px");
  synth->add_option("--bits", synth_args->bits, "pixel type: 8, 16 (integer, the default) or 32 (float)")->check(Count(8, 32));
  synth->add_option("--artefact", synth_args->artefact,
                    "height-map tiles of grid6x6 or bar17 instead (float, mm, 10 um pixels, NaN on steep flanks), "
                    "with calottes.csv, the true calottes");
  synth->add_option("--seed", synth_args->seed, "random seed")->check(Within(kSeed))->capture_default_str();
  synth->footer("Tiles are cut from one random texture with 30 % vignetting and 3 % noise; truth.csv holds the "
                "true top-left corners, the first tile at 0,0. With --artefact they are cut from one height map of "
                "the artefact (0.5 um of roughness, 0.1 um of noise per tile) and the layout holds the stage "
                "positions: fvm tiles synthesize --artefact grid6x6 -o g && cd g && fvm stitch --layout layout.csv "
                "--overlap 20 --pixel-mm 0.01 -o p.csv --mosaic m.x3p && fvm fit m.x3p --artefact grid6x6 -o c.csv\n"
                "Example:\n  fvm tiles synthesize -o demo --rows 3 --cols 4 --tile-px 512 --overlap 20 --seed 1");
  synth->callback([synth_args] { RunSynthesize(*synth_args); });
}

}  // namespace fvm::cli
