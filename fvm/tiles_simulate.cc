// fvm tiles simulate: the [Pérez 2019] stitching strategies on coordinates (artefacts/stitching_strategy.h) or on
// rendered tiles (artefacts/rendered_stitching_strategy.h).

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

struct StrategyArgs {
  std::string calibration;
  std::string lens = "10x";
  double overlap = 0.2;
  std::vector<double> from{-154.5487, -115.4767, -50.3624};  // [Pérez 2019] Table 1, case a, calotte 1
  std::vector<double> to{-134.5409, -115.4371, -50.4457};    // ... calotte 6
  bool render = false;
  std::string tiles_output;
  int tile_px = artefacts::RenderedStrategyOptions{}.tile_px;
  std::uint64_t seed = 1;
  bool json = false;
};

// The rendered row as a tile set for fvm stitch: 16-bit TIFFs and a layout whose x, y are the encoder readings of
// the tile centres, so that stitching them with the pixel size reproduces case a.
void WriteRenderedRow(const artefacts::RenderedStrategies& row, const artefacts::RenderedStrategyOptions& options,
                      const std::filesystem::path& directory) {
  std::vector<imaging::GridTile> grid;
  for (size_t i = 0; i < row.images.size(); ++i) grid.push_back({0, static_cast<int>(i), Eigen::Vector2d::Zero()});
  WriteTileSet(directory, row.images, grid, row.encoder_centres_mm, imaging::TilePixelType::kUint16,
               fmt::format("fvm tiles simulate --render --seed {}: the row of {} tiles of {} px, {:.6f} mm per px, "
                           "x,y = encoder readings of the tile centres (mm). Stitch with:\nfvm stitch --layout "
                           "layout.csv --overlap {:g} --pixel-mm {:.9g} -o positions.csv",
                           options.seed, row.images.size(), options.tile_px, row.pixel_mm,
                           options.geometry.overlap * 100, row.pixel_mm));
}

void RunStrategies(const StrategyArgs& args) {
  imaging::SetImagingThreads(ThreadCount());  // --render registers tiles on OpenCV's pool
  const stage::Calibration cal = stage::ReadCalibration(args.calibration);
  artefacts::RenderedStrategyOptions options;
  options.geometry.fov_mm = imaging::FindLens(args.lens).fov_mm;
  options.geometry.overlap = args.overlap > 1.0 ? args.overlap / 100.0 : args.overlap;
  options.tile_px = args.tile_px;
  options.seed = args.seed;
  const Eigen::Vector3d first(args.from[0], args.from[1], args.from[2]);
  const Eigen::Vector3d last(args.to[0], args.to[1], args.to[2]);
  if (!args.tiles_output.empty() && !args.render) throw InputError("--tiles needs --render");
  std::vector<artefacts::StrategyResult> results;
  std::optional<artefacts::RenderedStrategies> rendered;
  try {
    if (args.render) {
      if (!args.json) fmt::print(stderr, "rendering and registering the row's tiles ...\n");
      rendered = artefacts::SimulateRenderedStrategies(cal.layout, cal.values, first, last, options);
      for (const artefacts::RenderedStrategyResult& c : rendered->cases) results.push_back(c.coordinates);
    } else {
      results = artefacts::SimulateStitchingStrategies(cal.layout, cal.values, first, last, options.geometry);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles simulate: ") + e.what());
  }
  if (!args.tiles_output.empty()) WriteRenderedRow(*rendered, options, args.tiles_output);
  // The published differences ([Pérez 2019] Table 1, 6 x 6 grid, 10x lens, calottes 1 and 6), for comparison.
  const std::map<char, double> published = {{'b', -14.6}, {'c', -1.5}, {'d', -8.9}, {'e', -14.8}, {'f', -15.0}};
  nlohmann::ordered_json doc;
  doc["calibration"] = args.calibration;
  doc["fov_mm"] = options.geometry.fov_mm;
  doc["overlap"] = options.geometry.overlap;
  if (rendered) {
    doc["rendered"] = {{"tile_px", options.tile_px},
                       {"pixel_um", rendered->pixel_mm * 1e3},
                       {"row_tiles", rendered->row_tiles},
                       {"pair_rms_px", rendered->pair_rms_px},
                       {"rejected_pairs", rendered->rejected_pairs},
                       {"seed", options.seed}};
  }
  for (size_t k = 0; k < results.size(); ++k) {
    const artefacts::StrategyResult& r = results[k];
    nlohmann::ordered_json c = {{"case", std::string(1, r.id)}, {"description", r.description},
                                {"tiles", r.tiles},           {"encoder_tiles", r.encoder_tiles},
                                {"distance_mm", r.distance_mm}, {"diff_um", r.distance_error_um}};
    if (rendered) {
      const artefacts::RenderedStrategyResult& g = rendered->cases[k];
      c["rendered"] = {{"encoder_tiles", g.result.encoder_tiles}, {"distance_mm", g.result.distance_mm},
                       {"diff_um", g.result.distance_error_um},  {"pairs", g.pairs},
                       {"accepted_pairs", g.accepted_pairs}};
    }
    doc["cases"].push_back(c);
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("stitching strategies over {:.3f} mm with the {} lens ({} mm field, {:.0f} % overlap), stage model {} "
             "from {}\n",
             (last - first).norm(), args.lens, options.geometry.fov_mm, options.geometry.overlap * 100, cal.model,
             args.calibration);
  if (rendered) {
    fmt::print("rendered: {} tiles of {} px ({:.3f} um / px), neighbour pairs registered to {:.3f} px rms ({:.3f} um), "
               "{} rejected; seed {}\n",
               rendered->row_tiles, options.tile_px, rendered->pixel_mm * 1e3, rendered->pair_rms_px,
               rendered->pair_rms_px * rendered->pixel_mm * 1e3, rendered->rejected_pairs, options.seed);
  }
  fmt::print("\n  {:<4} {:<36} {:>5} {:>13} {:>10} {:>12} {:>14}\n", "case", "strategy", "tiles", "distance mm",
             "diff um", rendered ? "rendered um" : "", "published um");
  for (size_t k = 0; k < results.size(); ++k) {
    const artefacts::StrategyResult& r = results[k];
    const auto p = published.find(r.id);
    fmt::print("  {:<4} {:<36} {:>5} {:>13.4f} {:>10.1f} {:>12} {:>14}\n", r.id, r.description, r.tiles,
               r.distance_mm, r.distance_error_um,
               rendered ? fmt::format("{:.1f}", rendered->cases[k].result.distance_error_um) : "",
               p == published.end() ? "-" : fmt::format("{:.1f}", p->second));
  }
  fmt::print("\n  A tile that cannot be registered to its neighbour falls back to the encoders and carries the stage "
             "error there;\n  the error grows with the distance from the first tile to the last such tile.\n");
  if (rendered) {
    fmt::print("  'rendered' comes from images: tiles rendered where the stage really is, registered, and the calottes "
               "fitted in\n  their tiles; it differs from 'diff' by the registration and fit noise.\n");
  }
}

}  // namespace

void AddTilesSimulate(CLI::App* tiles) {
  auto strategy_args = std::make_shared<StrategyArgs>();
  CLI::App* strategies = tiles->add_subcommand(
      "simulate", "the end-to-end distance error of the six stitching strategies of [Pérez 2019] under a stage model");
  strategies->add_option("--calibration", strategy_args->calibration, "stage model: a file written by 'fvm calibrate -o'")
      ->required();
  strategies->add_option("--lens", strategy_args->lens, "lens (field of view from the lens table)")->capture_default_str();
  strategies->add_option("--overlap", strategy_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str();
  strategies->add_option("--from", strategy_args->from, "first calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 1)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_option("--to", strategy_args->to, "last calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 6)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_flag("--render", strategy_args->render,
                       "also render the row's tiles where the stage really puts them, register them as fvm stitch "
                       "does and fit the calottes in their tiles (a few seconds)");
  strategies->add_option("--tile-px", strategy_args->tile_px, "with --render: pixels across a tile")
      ->check(Count(16, 8192))
      ->capture_default_str();
  strategies->add_option("--tiles", strategy_args->tiles_output,
                         "with --render: write the row's tiles (16-bit TIFF) and layout.csv (encoder positions) to "
                         "this directory, ready for fvm stitch");
  strategies->add_option("--seed", strategy_args->seed, "with --render: seed of the texture and the noise")
      ->check(Within(kSeed))
      ->capture_default_str();
  strategies->add_flag("--json", strategy_args->json,
                       "print {\"cases\": [{\"case\", \"description\", \"tiles\", \"encoder_tiles\", "
                       "\"distance_mm\", \"diff_um\"[, \"rendered\": {\"encoder_tiles\", \"distance_mm\", "
                       "\"diff_um\", \"pairs\", \"accepted_pairs\"}]}][, \"rendered\": {\"tile_px\", "
                       "\"pixel_um\", \"row_tiles\", \"pair_rms_px\", \"rejected_pairs\", \"seed\"}]}");
  strategies->footer("Cases: a all stitched; b only the end tiles; c the tile after the first missing; d a middle "
                     "tile missing; e the tile before the last missing; f every other tile missing ([Pérez 2019] Tables 1-2).\n"
                     "Example:\n  fvm calibrate samples/bar17 --model 27 -o stage.json && fvm tiles simulate "
                     "--calibration stage.json --lens 10x --overlap 20 --render");
  strategies->callback([strategy_args] { RunStrategies(*strategy_args); });
}

}  // namespace fvm::cli
