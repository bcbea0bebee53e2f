// Focus variation on a 1024 x 1024 x 100 stack of 8-bit images (a plane rising 80 um through a 100 um stack,
// 1 um steps): the parallel reconstruction (stripes of rows on OpenCV's thread pool) against the same
// computation on one thread. Counters: megapixel-images per second and the height error against the truth.

#include <benchmark/benchmark.h>

#include <cmath>

#include "artefacts/simulation/focus_stack_render.h"
#include "imaging/focus_variation.h"

namespace {

struct Scene {
  fvm::imaging::HeightMap truth;
  fvm::artefacts::RenderedFocusStack stack;
  std::vector<fvm::imaging::StackImageView> views;
};

const Scene& Stack() {
  static const Scene scene = [] {
    Scene s;
    s.truth = fvm::artefacts::TiltedPlane(1024, 1024, 0.001, 0.010, 0.05, 0.03);  // 10 .. 92 um
    fvm::artefacts::FocusStackRenderOptions o;
    o.z_mm = fvm::artefacts::EvenZSteps(0.0, 0.001, 100);
    o.seed = 1;
    s.stack = fvm::artefacts::RenderFocusStack(s.truth, o);
    s.views = s.stack.Views();
    return s;
  }();
  return scene;
}

void BM_FocusStack(benchmark::State& state, fvm::imaging::FocusMeasure measure, bool parallel) {
  const Scene& scene = Stack();
  fvm::imaging::FocusVariationOptions options;
  options.measure = measure;
  options.parallel = parallel;
  fvm::imaging::FocusResult result;
  for (auto _ : state) {
    result = fvm::imaging::ReconstructFocusStack(scene.views, scene.stack.z_mm, options);
    benchmark::DoNotOptimize(result);
  }
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < result.height.z_mm.size(); ++i) {
    const double d = double(result.height.z_mm[i]) - scene.truth.z_mm[i];
    if (std::isfinite(d)) sum += d * d, ++n;
  }
  state.counters["Mpx_images_per_s"] = benchmark::Counter(
      1024.0 * 1024.0 * 100.0 * 1e-6 * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["rms_um"] = n > 0 ? 1e3 * std::sqrt(sum / double(n)) : 0.0;
  state.counters["valid"] = double(n) / double(result.height.z_mm.size());
}

using fvm::imaging::FocusMeasure;
BENCHMARK_CAPTURE(BM_FocusStack, laplacian_parallel, FocusMeasure::kModifiedLaplacian, true)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK_CAPTURE(BM_FocusStack, laplacian_single_thread_baseline, FocusMeasure::kModifiedLaplacian, false)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);
BENCHMARK_CAPTURE(BM_FocusStack, tenengrad_parallel, FocusMeasure::kTenengrad, true)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK_CAPTURE(BM_FocusStack, variance_parallel, FocusMeasure::kVariance, true)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
