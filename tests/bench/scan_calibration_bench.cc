// Calibration from three stitched scans of 70 tiles of 1024 x 1024 px (issue 21: under 30 s on 2 cores): the chain
// registration of the three scans, and the identification of model 27 from their displacements, apart. Baselines in
// the same run: the registration on one thread, and the identification that fits the chained positions as
// independent points (the fit the displacements replace). Rendering the tiles is set-up, not timed.

#include <benchmark/benchmark.h>

#include "artefacts/scan_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "stage/fvm_stage_models.h"

namespace {

using namespace fvm;

struct Scans {
  std::vector<artefacts::SimulatedScan> rendered;
  std::vector<artefacts::RegisteredScan> registered;
  double pixel_mm = 0.0;
};

const Scans& ThreeScans() {
  static const Scans scans = [] {
    artefacts::FvmBatchOptions batch;
    batch.validation_placements = 0;
    const artefacts::FvmBatchTruth t = artefacts::SimulateFvmBatch(batch).truth;
    const artefacts::StageTruth truth{t.layout, t.values, 0.3, 25.0};
    imaging::TilePlanOptions lens;
    lens.fov_mm = 2.82;  // 5x
    lens.overlap = 0.27;  // 70 tiles along 150 mm
    artefacts::ScanSimulationOptions options;
    options.pixel_mm = lens.fov_mm / options.tile_px;
    options.camera = artefacts::ScanTexture("ground");
    Scans s;
    s.pixel_mm = options.pixel_mm;
    s.rendered = artefacts::SimulateScans(truth, imaging::PlanCalibrationScans({}, lens), options);
    for (const auto& scan : s.rendered) {
      s.registered.push_back(artefacts::RegisterScan(scan.name, scan.encoder_mm, scan.images, s.pixel_mm, false));
    }
    return s;
  }();
  return scans;
}

void BM_RegisterScans(benchmark::State& state, bool parallel) {
  const Scans& s = ThreeScans();
  imaging::RegistrationOptions options;
  options.parallel = parallel;
  int tiles = 0;
  for (auto _ : state) {
    tiles = 0;
    for (const auto& scan : s.rendered) {
      benchmark::DoNotOptimize(imaging::RegisterTileChain(scan.images, artefacts::NominalOffsetsPx(scan.encoder_mm, s.pixel_mm), options));
      tiles += static_cast<int>(scan.images.size());
    }
  }
  state.counters["tiles"] = tiles;
}
BENCHMARK_CAPTURE(BM_RegisterScans, pool, true)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_RegisterScans, one_thread_baseline, false)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void BM_IdentifyFromScans(benchmark::State& state) {
  const Scans& s = ThreeScans();
  stage::IdentificationOptions options;
  options.frame = stage::StitchedFrame::kRotated;
  for (auto _ : state) {
    benchmark::DoNotOptimize(artefacts::IdentifyFromScans(stage::FvmModelLayout("27"), s.registered, s.pixel_mm, 0.0, options));
  }
}
BENCHMARK(BM_IdentifyFromScans)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IdentifyChainedPositionsBaseline(benchmark::State& state) {
  const Scans& s = ThreeScans();
  const stage::MeasurementSet set = artefacts::ScanPositions(s.registered, s.pixel_mm);
  stage::IdentificationOptions options;
  options.frame = stage::StitchedFrame::kRotated;
  options.anchor = stage::Anchor::kFirstTile;
  options.anchors = set.anchors;
  for (auto _ : state) benchmark::DoNotOptimize(stage::Identify(stage::FvmModelLayout("27"), set.observations, options));
}
BENCHMARK(BM_IdentifyChainedPositionsBaseline)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
