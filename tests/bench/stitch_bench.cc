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

// Issue 42: the whole stitch of the real confocal grid of ../shared/realdata/tiles/confocal-3x4 (12 colour tiles of
// 1024 x 1024 px, 17 pairs), as fvm stitch --overlap 10 does it after start-up: the tiles decoded from their files
// and averaged to grey, then registered and placed (workflows::StitchTiles), on all cores; the baseline is the same
// on one thread, timed in the same process before it. Counters: the ratio of the two (one thread's time over this
// one's: how many times faster), and the mean overlap NCC at the positions. Skipped where ../shared is absent.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <vector>

#include "imaging/io/tile_layout.h"
#include "workflows/stitch.h"

namespace {

struct ConfocalLayout {
  fvm::imaging::TileLayout layout;
  std::filesystem::path dir;
};

const ConfocalLayout& ConfocalFiles() {
  static const ConfocalLayout grid = [] {
    ConfocalLayout g;
    g.dir = std::filesystem::path(FVM_REALDATA_DIR) / "tiles" / "confocal-3x4";
    if (!std::filesystem::exists(g.dir)) return g;
    for (int k = 0; k < 12; ++k) {  // serpentine: the middle row runs right to left (its TileConfiguration.txt)
      const int row = k / 4, col = row == 1 ? 3 - k % 4 : k % 4;
      char file[64];
      std::snprintf(file, sizeof file, "x100_epr-jerem_10pct_001_A%03d_I.tif", k + 1);
      g.layout.tiles.push_back({file, row, col, std::nullopt, k + 2, std::nullopt});
    }
    g.layout.rows = 3, g.layout.cols = 4;
    return g;
  }();
  return grid;
}

// Decodes and stitches the grid on `threads` threads (0: all cores); returns the mean overlap NCC.
double StitchConfocal(int threads) {
  const ConfocalLayout& g = ConfocalFiles();
  fvm::workflows::StitchOptions options;
  options.overlap = 0.1;
  options.threads = threads;
  const std::vector<fvm::imaging::TileImage> images = fvm::imaging::ReadLayoutImages(g.layout, g.dir, nullptr, threads);
  return fvm::workflows::StitchTiles(g.layout, images, options).mean_overlap_ncc;
}

double SecondsOf(const std::function<void()>& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void BM_ConfocalWholeStitch(benchmark::State& state, int threads) {
  if (ConfocalFiles().layout.tiles.empty()) {
    state.SkipWithError("../shared/realdata absent");
    return;
  }
  StitchConfocal(1);  // the plugins loaded and the caches warm before either is timed
  // One thread and `threads` in turn, each iteration, so that both see the same machine.
  std::vector<double> one, many;
  double ncc = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    one.push_back(SecondsOf([] { StitchConfocal(1); }));
    state.ResumeTiming();
    many.push_back(SecondsOf([&] { ncc = StitchConfocal(threads); }));
  }
  std::sort(one.begin(), one.end());
  std::sort(many.begin(), many.end());
  state.counters["one_thread_ms"] = 1e3 * one[one.size() / 2];
  state.counters["times_faster"] = one[one.size() / 2] / many[many.size() / 2];
  state.counters["overlap_ncc"] = ncc;
  fvm::imaging::SetImagingThreads(0);
}

BENCHMARK_CAPTURE(BM_ConfocalWholeStitch, all_cores, 0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);
BENCHMARK_CAPTURE(BM_ConfocalWholeStitch, two_threads, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

}  // namespace
