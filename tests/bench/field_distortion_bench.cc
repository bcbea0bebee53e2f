// Issue 43: the real confocal grid of ../shared/realdata/tiles/confocal-3x4 (12 tiles of 1024 px, 17 pairs):
// fvm stitch's rigid registration (a baseline) against the same followed by the field distortion identified with
// the positions (fvm stitch --distortion: dense correspondences twice, two joint solves, the tiles resampled), on
// every core and on one thread (the other baseline: OpenCV's pool and Ceres both on one). Counters: the mean
// overlap correlation at the positions found, and for the field its largest displacement. The whole process is
// timed by fvm_startup_bench (BM_StitchConfocalDistortionVsOneThread). Skipped where ../shared is absent.

#include <benchmark/benchmark.h>
#include <fmt/core.h>

#include <filesystem>

#include "imaging/io/tile_image.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"

namespace {

struct ConfocalGrid {
  fvm::imaging::TileLayout layout;
  std::vector<fvm::imaging::TileImage> images;
};

const ConfocalGrid& Confocal() {
  static const ConfocalGrid grid = [] {
    ConfocalGrid g;
    const std::filesystem::path dir = std::filesystem::path(FVM_REALDATA_DIR) / "tiles" / "confocal-3x4";
    if (!std::filesystem::exists(dir)) return g;
    for (int k = 0; k < 12; ++k) {  // serpentine: the middle row runs right to left
      const int row = k / 4, col = row == 1 ? 3 - k % 4 : k % 4;
      const std::string file = fmt::format("x100_epr-jerem_10pct_001_A{:03d}_I.tif", k + 1);
      g.layout.tiles.push_back({file, row, col, std::nullopt, k + 2, std::nullopt});
      g.images.push_back(fvm::imaging::ReadTileImage(dir / file));
    }
    g.layout.rows = 3, g.layout.cols = 4;
    return g;
  }();
  return grid;
}

void BM_ConfocalStitch(benchmark::State& state, bool distortion, int threads) {
  const ConfocalGrid& g = Confocal();
  if (g.images.empty()) {
    state.SkipWithError("../shared/realdata absent");
    return;
  }
  fvm::workflows::StitchOptions options;
  options.overlap = 0.1;
  options.threads = threads;
  fvm::workflows::StitchDistortionOptions field;
  if (threads > 0) field.fit.threads = threads;
  double ncc = 0.0, largest = 0.0;
  for (auto _ : state) {
    const fvm::workflows::StitchResult rigid = fvm::workflows::StitchTiles(g.layout, g.images, options);
    ncc = rigid.mean_overlap_ncc;
    if (distortion) {
      const fvm::workflows::StitchDistortionResult r = fvm::workflows::StitchWithoutDistortion(rigid, g.images, field);
      ncc = r.mean_overlap_ncc_after;
      largest = r.fit.field.LargestDisplacementPx();
    }
  }
  state.counters["overlap_ncc"] = ncc;
  state.counters["largest_px"] = largest;
}

BENCHMARK_CAPTURE(BM_ConfocalStitch, rigid_baseline, false, 0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);
BENCHMARK_CAPTURE(BM_ConfocalStitch, with_field_distortion, true, 0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);
BENCHMARK_CAPTURE(BM_ConfocalStitch, with_field_distortion_one_thread_baseline, true, 1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace
