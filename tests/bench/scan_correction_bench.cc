// Correcting a 10-million-point cloud (issue 17): the scan path (stage::CorrectScanInPlace, every point by the
// model at its own stage coordinates, with its standard uncertainties, in place, on all cores) against the
// centre-CSV path of fvm correct (stage::Correct per centre and a CSV line each, one thread). Both run the same
// model on the same points in one process; items_per_second is points per second of wall-clock time, and the
// ratio is printed by BM_ScanOverCentreRatio.

#include <benchmark/benchmark.h>
#include <fmt/core.h>

#include <chrono>
#include <random>
#include <string>
#include <vector>

#include "stage/calibration.h"
#include "stage/scan_correction.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

// A first-order model (27 coefficients) with a covariance, over the published stage's travel.
Calibration Model27() {
  const ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 1);
  const Eigen::Index n = layout.NumFree();
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n) * 1e-4;
  return Calibration{"27", layout, testing::RandomCoefficients(layout, 1), a * a.transpose() * 1e-6, 5e-4, std::nullopt, {}};
}

std::vector<Eigen::Vector3d> Cloud(std::size_t n) {
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> x(-150.0, -50.0), y(-150.0, -50.0), z(-50.5, -49.5);
  std::vector<Eigen::Vector3d> points(n);
  for (Eigen::Vector3d& p : points) p = Eigen::Vector3d(x(random), y(random), z(random));
  return points;
}

void BM_ScanCorrection(benchmark::State& state) {
  const Calibration cal = Model27();
  const std::vector<Eigen::Vector3d> cloud = Cloud(static_cast<std::size_t>(state.range(0)));
  const bool uncertainties = state.range(1) != 0;
  const ScanCorrector corrector(cal, {}, cloud);
  std::vector<Eigen::Vector3d> points, u;
  for (auto _ : state) {
    state.PauseTiming();
    points = cloud;
    state.ResumeTiming();
    benchmark::DoNotOptimize(
        CorrectScanInPlace(corrector, points, uncertainties ? &u : nullptr, static_cast<int>(state.range(2))));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
  state.counters["u"] = uncertainties;
  state.counters["threads"] = static_cast<double>(state.range(2));
}
// Points, uncertainties (1) or positions only (0), threads (0: all cores; 1: its CPU time is the whole work, which
// a loaded machine does not change).
BENCHMARK(BM_ScanCorrection)
    ->Args({10'000'000, 1, 0})
    ->Args({10'000'000, 0, 0})
    ->Args({10'000'000, 1, 1})
    ->Args({10'000'000, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

// What fvm correct does per centre of a centre export: the correction with its covariance and the CSV line.
void BM_CentreCsvPath(benchmark::State& state) {
  const Calibration cal = Model27();
  const std::vector<Eigen::Vector3d> cloud = Cloud(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    std::string csv;
    int id = 0;
    for (const Eigen::Vector3d& q : cloud) {
      const CorrectedPoint p = Correct(cal, q);
      const Eigen::Vector3d u = p.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      csv += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}\n", ++id, p.position.x(), p.position.y(),
                         p.position.z(), u.x(), u.y(), u.z());
    }
    benchmark::DoNotOptimize(csv);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}
BENCHMARK(BM_CentreCsvPath)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

// Both in one run, so that the ratio compares like with like on a shared machine: points per second of the scan
// path (10 M points, uncertainties included) over the centre-CSV path (1 M centres).
void BM_ScanOverCentreRatio(benchmark::State& state) {
  const Calibration cal = Model27();
  const std::vector<Eigen::Vector3d> cloud = Cloud(10'000'000);
  const ScanCorrector corrector(cal, {}, cloud);
  for (auto _ : state) {
    std::vector<Eigen::Vector3d> points = cloud, u;
    const auto t0 = std::chrono::steady_clock::now();
    CorrectScanInPlace(corrector, points, &u);
    const auto t1 = std::chrono::steady_clock::now();
    std::string csv;
    for (std::size_t i = 0; i < 1'000'000; ++i) {
      const CorrectedPoint p = Correct(cal, cloud[i]);
      const Eigen::Vector3d s = p.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      csv += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}\n", i + 1, p.position.x(), p.position.y(),
                         p.position.z(), s.x(), s.y(), s.z());
    }
    const auto t2 = std::chrono::steady_clock::now();
    const double scan = 1e7 / std::chrono::duration<double>(t1 - t0).count();
    const double centre = 1e6 / std::chrono::duration<double>(t2 - t1).count();
    state.counters["scan_points_per_s"] = scan;
    state.counters["centre_points_per_s"] = centre;
    state.counters["ratio"] = scan / centre;
  }
}
BENCHMARK(BM_ScanOverCentreRatio)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace fvm::stage
