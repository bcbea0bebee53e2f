// fvm fit --shape on 1 million points: the orthogonal-distance sphere (start, Levenberg-Marquardt on the normal
// equations, long-double Gauss-Newton polish) and the plane, against a baseline in the same run: the algebraic
// sphere alone (one pass over the points and a 4 x 4 solve), the floor of any fit that looks at every point.

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "imaging/shape_fit.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {
namespace {

const Eigen::Vector3d kBallCentre(412.345, -87.654, 231.5);
constexpr double kBallRadius = 12.5;

// A 60-degree cap of 1 million points with 2 um noise along the normal, at random directions (fixed seed).
const std::vector<Eigen::Vector3d>& MillionPoints(bool plane) {
  static const auto make = [](bool flat) {
    std::vector<Eigen::Vector3d> p;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.002);
    const double min_cos = std::cos(60 * M_PI / 180);
    for (int i = 0; i < 1000000; ++i) {
      const double cos_t = 1 - (1 - min_cos) * uniform(rng), phi = 2 * M_PI * uniform(rng);
      const double sin_t = std::sqrt(1 - cos_t * cos_t);
      const Eigen::Vector3d u(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
      p.push_back(flat ? Eigen::Vector3d(kBallCentre + 20 * u.cwiseProduct(Eigen::Vector3d(1, 1, 0)) + noise(rng) * Eigen::Vector3d::UnitZ())
                       : Eigen::Vector3d(kBallCentre + (kBallRadius + noise(rng)) * u));
    }
    return p;
  };
  static const std::vector<Eigen::Vector3d> sphere = make(false), flat = make(true);
  return plane ? flat : sphere;
}

void BM_ShapeFitSphere1M(benchmark::State& state) {
  const std::vector<Eigen::Vector3d>& points = MillionPoints(false);
  ShapeFit fit;
  for (auto _ : state) {
    fit = FitShape(points);
    benchmark::DoNotOptimize(fit.centre_mm);
  }
  state.counters["radius_err_nm"] = std::abs(fit.radius_mm - kBallRadius) * 1e6;
  state.counters["u_radius_nm"] = fit.u_radius_mm * 1e6;
}
BENCHMARK(BM_ShapeFitSphere1M)->Unit(benchmark::kMillisecond);

void BM_ShapeFitPlane1M(benchmark::State& state) {
  const std::vector<Eigen::Vector3d>& points = MillionPoints(true);
  ShapeFitOptions options;
  options.shape = Shape::kPlane;
  ShapeFit fit;
  for (auto _ : state) {
    fit = FitShape(points, options);
    benchmark::DoNotOptimize(fit.normal);
  }
  state.counters["normal_err_nrad"] = std::acos(std::min(1.0, fit.normal.z())) * 1e9;
}
BENCHMARK(BM_ShapeFitPlane1M)->Unit(benchmark::kMillisecond);

// The baseline: the algebraic sphere alone.
void BM_AlgebraicSphere1M(benchmark::State& state) {
  const std::vector<Eigen::Vector3d>& points = MillionPoints(false);
  Sphere sphere;
  for (auto _ : state) {
    sphere = FitSphereAlgebraic(points);
    benchmark::DoNotOptimize(sphere.centre_mm);
  }
  state.counters["radius_err_nm"] = std::abs(sphere.radius_mm - kBallRadius) * 1e6;
}
BENCHMARK(BM_AlgebraicSphere1M)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fvm::imaging
