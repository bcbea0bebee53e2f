// Registration of a 5 x 5 grid of 1024 x 1024 tiles (40 neighbour pairs): phase correlation of the overlap with
// sub-pixel refinement (what fvm stitch does), without the refinement, and the baseline of correlating the full
// frames; then the published 225-tile grid (15 x 15, 420 pairs) once on the thread pool and once on one thread.
// Counters: seconds per pair and the RMS position error against the synthetic truth.

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>

#include "artefacts/simulation/tile_synthesis.h"
#include "imaging/tile_registration.h"

namespace {

const fvm::artefacts::SynthesizedTiles& Grid(int n) {
  static std::map<int, fvm::artefacts::SynthesizedTiles> grids;
  if (!grids.contains(n)) {
    fvm::artefacts::TileSynthesisOptions options;
    options.rows = options.cols = n;
    options.width = options.height = 1024;
    options.overlap = 0.2;
    options.camera.components = 24;  // texture enough for registration; keeps the set-up to a few seconds
    options.seed = 1;
    grids.emplace(n, fvm::artefacts::SynthesizeTiles(options));
  }
  return grids.at(n);
}

void BM_RegisterGrid(benchmark::State& state, int n, bool crop, bool refine, bool parallel) {
  const auto& tiles = Grid(n);
  fvm::imaging::RegistrationOptions options;
  options.crop_to_overlap = crop;
  options.refine = refine;
  options.parallel = parallel;
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

// Single-threaded, so that the per-pair figures compare methods, not thread counts.
BENCHMARK_CAPTURE(BM_RegisterGrid, overlap_refined, 5, true, true, false)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_RegisterGrid, overlap_peak_only, 5, true, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_RegisterGrid, full_frame_baseline, 5, false, false, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// What fvm stitch does (pairs on OpenCV's thread pool) against one thread, on the published 225-tile grid.
BENCHMARK_CAPTURE(BM_RegisterGrid, published_225_tiles_parallel, 15, true, true, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_RegisterGrid, published_225_tiles_one_thread, 15, true, true, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

// Issue 30: the real strip of ../shared/realdata/tiles/starrynight (10 camera tiles of 594 x 929 px, steps 242-358
// px for a nominal 297, a printed grid that repeats): what fvm stitch does (pairs on the thread pool) against the
// same on one thread, the baseline. Counters: pairs accepted and the mean overlap correlation at the positions.
#include "imaging/overlap_correlation.h"
#include "tests/support/starrynight_strip.h"

namespace {

void BM_RegisterRealStrip(benchmark::State& state, bool parallel) {
  static const fvm::imaging::testing::RealStrip strip = fvm::imaging::testing::LoadStarrynight();
  if (strip.images.empty()) {
    state.SkipWithError("../shared/realdata absent");
    return;
  }
  fvm::imaging::RegistrationOptions options;
  options.parallel = parallel;
  fvm::imaging::RegistrationResult result;
  for (auto _ : state) {
    result = fvm::imaging::RegisterTileGrid(strip.images, strip.tiles, options);
    benchmark::DoNotOptimize(result);
  }
  int accepted = 0;
  for (const auto& pair : result.pairs) accepted += pair.accepted;
  double mean = 0.0;
  const auto ncc = fvm::imaging::NeighbourOverlapNcc(strip.images, strip.tiles, result.positions.positions_px);
  for (const auto& o : ncc) mean += o.correlation.ncc / static_cast<double>(ncc.size());
  state.counters["accepted"] = accepted;
  state.counters["overlap_ncc"] = mean;
}

BENCHMARK_CAPTURE(BM_RegisterRealStrip, pool, true)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK_CAPTURE(BM_RegisterRealStrip, one_thread_baseline, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

}  // namespace
