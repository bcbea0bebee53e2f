// Registration of a 5 x 5 grid of 1024 x 1024 tiles (40 neighbour pairs): phase correlation of the overlap with
// sub-pixel refinement (what fvm stitch does), without the refinement, and the baseline of correlating the full
// frames. Counters: seconds per pair and the RMS position error against the synthetic truth.

#include <benchmark/benchmark.h>

#include <cmath>

#include "artefacts/tile_synthesis.h"
#include "imaging/tile_registration.h"

namespace {

const fvm::artefacts::SynthesizedTiles& Grid() {
  static const fvm::artefacts::SynthesizedTiles tiles = [] {
    fvm::artefacts::TileSynthesisOptions options;
    options.rows = options.cols = 5;
    options.width = options.height = 1024;
    options.overlap = 0.2;
    options.components = 24;  // texture enough for registration; keeps the set-up to a few seconds
    options.seed = 1;
    return fvm::artefacts::SynthesizeTiles(options);
  }();
  return tiles;
}

void BM_RegisterGrid(benchmark::State& state, bool crop, bool refine) {
  const auto& tiles = Grid();
  fvm::imaging::RegistrationOptions options;
  options.crop_to_overlap = crop;
  options.refine = refine;
  fvm::imaging::RegistrationResult result;
  for (auto _ : state) {
    result = fvm::imaging::RegisterTileGrid(tiles.images, tiles.tiles, options);
    benchmark::DoNotOptimize(result);
  }
  double sum = 0.0;
  for (size_t i = 0; i < tiles.truth_px.size(); ++i) {
    sum += (result.positions.positions_px[i] - tiles.truth_px[i]).squaredNorm();
  }
  state.counters["pairs"] = static_cast<double>(result.pairs.size());
  state.counters["s_per_pair"] = benchmark::Counter(static_cast<double>(result.pairs.size()) * state.iterations(),
                                                    benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["rms_px"] = std::sqrt(sum / static_cast<double>(tiles.truth_px.size()));
}

BENCHMARK_CAPTURE(BM_RegisterGrid, overlap_refined, true, true)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RegisterGrid, overlap_peak_only, true, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RegisterGrid, full_frame_baseline, false, false)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
