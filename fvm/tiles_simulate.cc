// fvm tiles simulate: the [Pérez 2019] stitching strategies on coordinates or on rendered tiles
// (workflows/stitching_strategies.h).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "workflows/stitching_strategies.h"

namespace fvm::cli {
namespace {

struct StrategyArgs {
  workflows::StitchingStrategiesOptions job;
  bool json = false;
};

void RunStrategies(StrategyArgs& args) {
  args.job.threads = ThreadCount();
  const workflows::StitchingStrategies strategies = workflows::SimulateStitchingStrategies(args.job, [&] {
    if (!args.json) fmt::print(stderr, "rendering and registering the row's tiles ...\n");
  });
  const workflows::Summary summary = workflows::Summarize(strategies);
  if (args.json) {
    fmt::print("{}\n", summary.json.dump(2));
  } else {
    fmt::print("{}", summary.text);
  }
}

}  // namespace

void AddTilesSimulate(CLI::App* tiles) {
  auto strategy_args = std::make_shared<StrategyArgs>();
  CLI::App* strategies = tiles->add_subcommand(
      "simulate", "the end-to-end distance error of the six stitching strategies of [Pérez 2019] under a stage model");
  strategies->add_option("--calibration", strategy_args->job.calibration, "stage model: a file written by 'fvm calibrate -o'")
      ->required();
  strategies->add_option("--lens", strategy_args->job.lens, "lens (field of view from the lens table)")->capture_default_str();
  strategies->add_option("--overlap", strategy_args->job.overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str();
  strategies->add_option("--from", strategy_args->job.from, "first calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 1)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_option("--to", strategy_args->job.to, "last calotte x,y,z in mm (default: [Pérez 2019] Table 1, calotte 6)")
      ->check(Within(kCoordinateMm))
      ->delimiter(',')
      ->expected(3);
  strategies->add_flag("--render", strategy_args->job.render,
                       "also render the row's tiles where the stage really puts them, register them as fvm stitch "
                       "does and fit the calottes in their tiles (a few seconds)");
  strategies->add_option("--tile-px", strategy_args->job.tile_px, "with --render: pixels across a tile")
      ->check(Count(16, 8192))
      ->capture_default_str();
  strategies->add_option("--tiles", strategy_args->job.tiles,
                         "with --render: write the row's tiles (16-bit TIFF) and layout.csv (encoder positions) to "
                         "this directory, ready for fvm stitch");
  strategies->add_option("--seed", strategy_args->job.seed, "with --render: seed of the texture and the noise")
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
