// Jacobian of the forward model w.r.t. the free coefficients: automatic differentiation through the 21 term
// values (what identification uses) against central finite differences of the same model (the baseline).

#include <benchmark/benchmark.h>

#include "stage/parameter_layout.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

ParameterLayout Layout42() {
  ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 2);
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, Basis::kPower, 2);
  for (const char* c : {"xTy1", "xTz1", "yTz1"}) layout.Drop(c);
  return layout;  // 15 components of order 2 minus 3 aliased linear straightness terms: 42
}

void BM_JacobianAutodiff(benchmark::State& state) {
  const ParameterLayout layout = Layout42();
  const std::vector<double> free = testing::RandomCoefficients(layout, 1);
  Eigen::Vector3d q(-120, -80, -50);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ForwardJacobian(layout, free.data(), q));
    q.x() += 1e-9;
  }
  state.counters["params"] = layout.NumFree();
}
BENCHMARK(BM_JacobianAutodiff);

void BM_JacobianCentralDifferences(benchmark::State& state) {
  const ParameterLayout layout = Layout42();
  std::vector<double> free = testing::RandomCoefficients(layout, 1);
  Eigen::Vector3d q(-120, -80, -50);
  Eigen::MatrixXd j(3, layout.NumFree());
  for (auto _ : state) {
    for (int i = 0; i < layout.NumFree(); ++i) {
      const double keep = free[static_cast<size_t>(i)];
      free[static_cast<size_t>(i)] = keep + 1e-6;
      const Eigen::Vector3d up = Forward(layout, free.data(), q);
      free[static_cast<size_t>(i)] = keep - 1e-6;
      j.col(i) = (up - Forward(layout, free.data(), q)) / 2e-6;
      free[static_cast<size_t>(i)] = keep;
    }
    benchmark::DoNotOptimize(j);
    q.x() += 1e-9;
  }
  state.counters["params"] = layout.NumFree();
}
BENCHMARK(BM_JacobianCentralDifferences);

void BM_Forward(benchmark::State& state) {
  const ParameterLayout layout = Layout42();
  const std::vector<double> free = testing::RandomCoefficients(layout, 1);
  Eigen::Vector3d q(-120, -80, -50);
  for (auto _ : state) {
    benchmark::DoNotOptimize(Forward(layout, free.data(), q));
    q.x() += 1e-9;
  }
}
BENCHMARK(BM_Forward);

}  // namespace
}  // namespace fvm::stage
