// Identification of the 42-parameter model from 10 000 centre pairs: ours (rank treatment + Levenberg-Marquardt
// with automatic derivatives through the chain) against a Levenberg-Marquardt baseline with numeric (central)
// derivatives of the same model on the same data, in the same run.

#include <benchmark/benchmark.h>
#include <ceres/ceres.h>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "stage/fvm_stage_models.h"
#include "stage/identification.h"

namespace fvm::stage {
namespace {

// 588 bar placements over the stage, each anchored at its own first tile.
const stage::MeasurementSet& TenThousandPairs() {
  static const stage::MeasurementSet set = [] {
    artefacts::FvmBatchOptions options;
    options.seed = 5;
    options.validation_placements = 585;  // + 3 identification placements = 588 x 17 = 9996 centres
    const artefacts::SimulatedFvmBatch sim = artefacts::SimulateFvmBatch(options);
    std::vector<std::string> all = sim.batch.identify;
    all.insert(all.end(), sim.batch.validate.begin(), sim.batch.validate.end());
    return artefacts::Observations(sim.batch, all);
  }();
  return set;
}

IdentificationOptions Anchored() {
  IdentificationOptions options;
  options.anchor = Anchor::kFirstTile;
  options.anchors = TenThousandPairs().anchors;
  return options;
}

void BM_Identify42(benchmark::State& state) {
  const std::vector<Observation>& obs = TenThousandPairs().observations;
  const ParameterLayout layout = FvmModelLayout("42");
  for (auto _ : state) {
    const IdentificationResult r = Identify(layout, obs, Anchored());
    benchmark::DoNotOptimize(r.residual_summary.rms_mm);
    state.counters["rms_um"] = r.residual_summary.rms_um();
    state.counters["free"] = r.calibration.layout.NumFree();
  }
  state.counters["centres"] = static_cast<double>(obs.size());
}
BENCHMARK(BM_Identify42)->Unit(benchmark::kMillisecond);

struct NumericPointError {
  const ParameterLayout* layout;
  const Observation* observation;
  const Eigen::Vector3d* anchor;
  bool operator()(double const* const* parameters, double* residuals) const {
    const Eigen::Vector3d r = ModelResidual(*layout, parameters[0], *observation, anchor);
    for (int k = 0; k < 3; ++k) residuals[k] = r[k];
    return true;
  }
};

// The baseline gets the well-posed problem for free: the layout our rank treatment produced.
void BM_Identify42NumericBaseline(benchmark::State& state) {
  const std::vector<Observation>& obs = TenThousandPairs().observations;
  const ParameterLayout layout = Identify(FvmModelLayout("42"), obs, Anchored()).calibration.layout;
  for (auto _ : state) {
    std::vector<double> x(static_cast<size_t>(layout.NumFree()), 0.0);
    ceres::Problem problem;
    for (const Observation& o : obs) {
      auto* cost = new ceres::DynamicNumericDiffCostFunction<NumericPointError, ceres::CENTRAL>(
          new NumericPointError{&layout, &o, &TenThousandPairs().anchors[static_cast<size_t>(o.group)]});
      cost->AddParameterBlock(layout.NumFree());
      cost->SetNumResiduals(3);
      problem.AddResidualBlock(cost, nullptr, x.data());
    }
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    options.num_threads = 2;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    state.counters["rms_um"] = std::sqrt(2 * summary.final_cost / static_cast<double>(obs.size())) * 1e3;
    state.counters["iterations"] = static_cast<double>(summary.iterations.size());
  }
  state.counters["centres"] = static_cast<double>(obs.size());
}
BENCHMARK(BM_Identify42NumericBaseline)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fvm::stage
