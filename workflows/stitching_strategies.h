#pragma once
// `fvm tiles simulate`: the end-to-end distance error of the six stitching strategies of [Pérez 2019] under a
// calibrated stage model, on coordinates (artefacts/simulation/stitching_strategy.h) and, with `render`, on tiles
// rendered where the stage really puts them, registered and fitted (artefacts/simulation/rendered_stitching_strategy.h).
// Its summary (the --json document and the printed text) beside the published differences, for every front end.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/simulation/rendered_stitching_strategy.h"
#include "artefacts/simulation/stitching_strategy.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct StitchingStrategiesOptions {
  std::string calibration;  // --calibration: a file written by fvm calibrate -o
  std::string lens = "10x";
  double overlap = 0.2;  // --overlap: a fraction, or percent above 1
  std::vector<double> from{-154.5487, -115.4767, -50.3624};  // [Pérez 2019] Table 1, case a, calotte 1 (x, y, z mm)
  std::vector<double> to{-134.5409, -115.4371, -50.4457};    // ... calotte 6
  bool render = false;
  int tile_px = artefacts::RenderedStrategyOptions{}.tile_px;  // with render: pixels across a tile
  std::string tiles;  // --tiles DIR: with render, write the row's tiles and layout.csv for fvm stitch
  std::uint64_t seed = 1;
  int threads = 0;  // OpenCV's pool for the registration; 0: all cores
  void Check() const;  // InputError naming --from / --to / --tile-px / --threads
};

struct StitchingStrategies {
  StitchingStrategiesOptions options;
  std::string model;  // the calibration's stage model
  artefacts::RenderedStrategyOptions rendering;  // field, overlap (a fraction), tile size, seed
  std::vector<artefacts::StrategyResult> results;  // cases a-f on coordinates
  std::optional<artefacts::RenderedStrategies> rendered;  // with render
};

// Reads the calibration and the lens (InputError naming them), refuses --tiles without --render, simulates;
// `before_rendering` is called before the tiles are rendered (a few seconds). Writes the rendered row to `tiles`.
StitchingStrategies SimulateStitchingStrategies(const StitchingStrategiesOptions& options,
                                                const std::function<void()>& before_rendering = {});

Summary Summarize(const StitchingStrategies& strategies);

}  // namespace fvm::workflows
