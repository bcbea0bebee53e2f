// Identification of the published models on simulated batches with a recorded truth (artefacts/).

#include "stage/identification.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "artefacts/batch_observations.h"
#include "artefacts/fvm_batch_simulation.h"
#include "stage/fvm_stage_models.h"
#include "stage/validation.h"

namespace fvm::stage {
namespace {

struct Experiment {
  artefacts::SimulatedFvmBatch sim;
  artefacts::ObservationSet identify, validate;
};

Experiment Simulate(unsigned seed, const std::string& truth = "27", double noise_um = 0.5, bool same_start = true) {
  artefacts::FvmBatchOptions options;
  options.seed = seed;
  options.truth_model = truth;
  options.noise_um = noise_um;
  options.same_start = same_start;
  Experiment e{artefacts::SimulateFvmBatch(options), {}, {}};
  e.identify = artefacts::Observations(e.sim.batch, e.sim.batch.identify);
  e.validate = artefacts::Observations(e.sim.batch, e.sim.batch.validate);
  return e;
}

IdentificationOptions AnchorOptions(const artefacts::ObservationSet& set, Anchor anchor) {
  IdentificationOptions o;
  o.anchor = anchor;
  o.anchors = set.anchors;
  return o;
}

TEST(Identification, ExploreModels) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Experiment e = Simulate(seed);
    const ValidationStats before = Validate(nullptr, e.validate.observations, e.validate.anchors);
    std::printf("seed %u truth mean %.1f max %.1f um; validation before %.1f um\n", seed, e.sim.truth.mean_error_um,
                e.sim.truth.max_error_um, before.mean_mm * 1e3);
    for (const std::string& model : FvmModelNames()) {
      const IdentificationResult r = Identify(FvmModelLayout(model), e.identify.observations);
      const ValidationStats v = Validate(&r.calibration, e.validate.observations, e.validate.anchors);
      std::printf("  %s: free %d fixed %zu id rms %.2f um val mean %.2f rms %.2f pred %.2f cond %.3g it %d conv %d\n", model.c_str(),
                  r.calibration.layout.NumFree(), r.fixed.size(), r.rms_mm * 1e3, v.mean_mm * 1e3, v.rms_mm * 1e3,
                  v.predicted_rms_mm * 1e3, r.condition_number, r.iterations, r.converged);
      if (model == "27" && seed == 1) std::printf("%s\n", r.solver_report.c_str());
    }
  }
}

}  // namespace
}  // namespace fvm::stage
