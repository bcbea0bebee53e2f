// Machine-tool verification of issue 10: the 21 error functions (Legendre, order 3) and the tracker pose
// identified from 5408 simulated tracker readings ([IJSIMM 2016] Table IV: XFYZ, 2500 x 1500 x 1200 mm, mesh of 100 mm,
// tool 0,0,100 mm, tracker at [IJSIMM 2016] Table I position 4 with the published noise), by ours
// (stage::VerifyMachine: rank treatment, then Ceres' Levenberg-Marquardt with analytic-through-autodiff Jacobians)
// against a plain Levenberg-Marquardt with central-difference Jacobians of the same forward model (stage::ChainForward
// + pose), the same weights (each reading whitened by its tracker covariance) and the same free coefficients, in the
// same run. Both run on one thread: the comparison is of the algorithms, not of the cores a shared machine lends.
//
// The baseline is given the well-posed problem for free (the layout our rank treatment produced) and starts where
// a user would: zero errors and the rigid best-fit pose. The check: both reach the same cost (1/2 chi^2) within
// 1e-6 relative, or the benchmark fails.

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <vector>

#include "artefacts/simulation/machine_tool_simulation.h"
#include "stage/machine_verification.h"
#include "stage/tracker.h"

namespace fvm::stage {
namespace {

constexpr int kPose = 6;

struct Readings {
  AxisChain chain;  // XFYZ with the tool offset, no instrument: the pose is what the fits estimate
  std::array<Travel, 3> travel;
  std::vector<Observation> observations;  // with the published tracker covariances
};

const Readings& FiveThousandReadings() {
  static const Readings readings = [] {
    Readings r;
    r.chain = AxisChain::Parse("XFYZ");
    r.chain.tool_offset = Eigen::Vector3d(0, 0, 100);
    const artefacts::Workspace ws;  // 2500 x 1500 x 1200 mm from the origin
    for (int k = 0; k < 3; ++k) r.travel[static_cast<size_t>(k)] = Travel{ws.min[k], ws.max[k]};
    AxisChain measured = r.chain;
    measured.instrument = Pose::FromEulerXyzDegrees(Eigen::Vector3d(1100, -1000, 600), Eigen::Vector3d(63, 14, 35));
    const artefacts::MachineTruth truth = artefacts::RandomMachineTruth(r.chain, ws, 1);
    const std::vector<artefacts::PlannedPoint> points = artefacts::PlanMesh(ws, Eigen::Vector3d(100, 100, 100));
    const TrackerNoise noise = TrackerNoise::Preset("published");
    const artefacts::TrackerReadings tracker = artefacts::SimulateTrackerReadings(measured, truth, points, noise, 2);
    for (const artefacts::TrackerReading& p : tracker.points) {
      Observation o;
      o.command = p.nominal;
      o.measured = p.measured;
      o.covariance = noise.Covariance(p.measured);
      r.observations.push_back(o);
    }
    return r;
  }();
  return readings;
}

// The layout `fvm verify --order 3 --basis legendre` builds.
ParameterLayout Order3Legendre() {
  const Readings& r = FiveThousandReadings();
  ParameterLayout layout(r.chain, r.travel);
  for (const char* axis : {"x", "y", "z"}) {
    for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"})
      layout.SetTerm(std::string(axis) + kind, Basis::kLegendre, 3);
  }
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, Basis::kLegendre, 0);
  return layout;
}

IdentificationOptions Estimated() {
  IdentificationOptions options;
  options.instrument = InstrumentPose::kEstimated;
  options.tool_offsets = {FiveThousandReadings().chain.tool_offset};
  options.num_threads = 1;
  return options;
}

const VerificationResult& Ours() {
  static const VerificationResult result =
      VerifyMachine(Order3Legendre(), FiveThousandReadings().observations, Estimated());
  return result;
}

// The numeric baseline's problem: whitened residuals of the forward model at (free coefficients, pose6).
class WhitenedModel {
 public:
  explicit WhitenedModel(const ParameterLayout& layout) : layout_(layout) {
    for (const Observation& o : FiveThousandReadings().observations) {
      whiten_.push_back(Eigen::LLT<Eigen::Matrix3d>(o.covariance).matrixL().solve(Eigen::Matrix3d::Identity()));
    }
  }
  int Parameters() const { return layout_.NumFree() + kPose; }
  Eigen::VectorXd Residuals(const Eigen::VectorXd& x) const {
    const std::vector<Observation>& obs = FiveThousandReadings().observations;
    const int n = layout_.NumFree();
    std::vector<double> all(layout_.coefficients().size(), 0.0);
    layout_.Expand(x.data(), all.data());
    Eigen::VectorXd r(3 * static_cast<Eigen::Index>(obs.size()));
    double e[kNumErrorTerms];
    for (size_t i = 0; i < obs.size(); ++i) {
      layout_.TermValues(all.data(), obs[i].command, e);
      r.segment<3>(3 * static_cast<Eigen::Index>(i)) =
          whiten_[i] * (ChainForward(layout_.chain(), e, obs[i].command, x.data() + n) - obs[i].measured);
    }
    return r;
  }

 private:
  const ParameterLayout& layout_;
  std::vector<Eigen::Matrix3d> whiten_;
};

// Levenberg-Marquardt (Marquardt's scaling of the damping by diag(J^T J)) with central-difference Jacobians, steps
// of 1e-4 of each parameter's plausible size (PlausibleSizes; 1 mm and 1 mrad for the pose).
struct NumericFit {
  Eigen::VectorXd x;
  double cost = 0;
  int iterations = 0, evaluations = 0;
};
NumericFit NumericLevenbergMarquardt(const WhitenedModel& model, Eigen::VectorXd x, const Eigen::VectorXd& typical) {
  NumericFit fit;
  const Eigen::Index p = x.size();
  Eigen::VectorXd r = model.Residuals(x);
  ++fit.evaluations;
  double cost = 0.5 * r.squaredNorm();
  double lambda = 1e-3;
  Eigen::MatrixXd j(r.size(), p);
  for (fit.iterations = 1; fit.iterations <= 100; ++fit.iterations) {
    for (Eigen::Index c = 0; c < p; ++c) {
      const double h = 1e-4 * typical[c];
      Eigen::VectorXd plus = x, minus = x;
      plus[c] += h;
      minus[c] -= h;
      j.col(c) = (model.Residuals(plus) - model.Residuals(minus)) / (2 * h);
      fit.evaluations += 2;
    }
    const Eigen::MatrixXd normal = j.transpose() * j;
    const Eigen::VectorXd gradient = j.transpose() * r;
    bool improved = false;
    double reduction = 0;
    while (lambda < 1e16) {
      Eigen::MatrixXd damped = normal;
      damped.diagonal() += lambda * normal.diagonal();
      const Eigen::VectorXd step = -damped.ldlt().solve(gradient);
      const Eigen::VectorXd trial = x + step;
      const Eigen::VectorXd r_trial = model.Residuals(trial);
      ++fit.evaluations;
      const double trial_cost = 0.5 * r_trial.squaredNorm();
      if (trial_cost < cost) {
        reduction = (cost - trial_cost) / cost;
        x = trial;
        r = r_trial;
        cost = trial_cost;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        break;
      }
      lambda *= 10;
    }
    if (!improved || reduction < 1e-10) break;
  }
  fit.x = x;
  fit.cost = cost;
  return fit;
}

void BM_VerifyOrder3(benchmark::State& state) {
  const std::vector<Observation>& obs = FiveThousandReadings().observations;
  const ParameterLayout layout = Order3Legendre();
  for (auto _ : state) {
    const VerificationResult v = VerifyMachine(layout, obs, Estimated());
    benchmark::DoNotOptimize(v.final.mean_um());
    const double dof = 3.0 * static_cast<double>(obs.size()) - v.identified.calibration.layout.NumFree() - kPose;
    state.counters["cost"] = 0.5 * v.identified.weighted_rms * v.identified.weighted_rms * dof;
    state.counters["final_mean_um"] = v.final.mean_um();
    state.counters["free"] = v.identified.calibration.layout.NumFree();
    state.counters["iterations"] = v.identified.iterations;
  }
  state.counters["points"] = static_cast<double>(obs.size());
}
BENCHMARK(BM_VerifyOrder3)->Unit(benchmark::kMillisecond);

void BM_VerifyOrder3NumericBaseline(benchmark::State& state) {
  const std::vector<Observation>& obs = FiveThousandReadings().observations;
  const VerificationResult& ours = Ours();
  const ParameterLayout& layout = ours.identified.calibration.layout;  // the free coefficients ours kept
  const WhitenedModel model(layout);
  Eigen::VectorXd typical(model.Parameters());
  typical << PlausibleSizes(layout), 1, 1, 1, 1e-3, 1e-3, 1e-3;
  // Ours' cost, evaluated by the baseline's own residuals.
  Eigen::VectorXd ours_x(model.Parameters());
  const Pose& pose = ours.identified.pose;
  ours_x << Eigen::Map<const Eigen::VectorXd>(ours.identified.calibration.values.data(), layout.NumFree()),
      pose.translation, pose.rotation;
  const double ours_cost = 0.5 * model.Residuals(ours_x).squaredNorm();
  NumericFit fit;
  for (auto _ : state) {
    const Pose start = RigidStartPose(layout.chain(), obs, {layout.chain().tool_offset});
    Eigen::VectorXd x = Eigen::VectorXd::Zero(model.Parameters());
    x.tail<kPose>() << start.translation, start.rotation;
    fit = NumericLevenbergMarquardt(model, x, typical);
    benchmark::DoNotOptimize(fit.cost);
  }
  const double relative = std::abs(fit.cost - ours_cost) / ours_cost;
  state.counters["cost"] = fit.cost;
  state.counters["ours_cost"] = ours_cost;
  state.counters["cost_rel_diff"] = relative;
  state.counters["iterations"] = fit.iterations;
  state.counters["evaluations"] = fit.evaluations;
  state.counters["points"] = static_cast<double>(obs.size());
  if (!(relative <= 1e-6)) state.SkipWithError("the numeric baseline and ours reach different costs (> 1e-6 relative)");
}
BENCHMARK(BM_VerifyOrder3NumericBaseline)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fvm::stage
