#include "workflows/model_choice.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "artefacts/batch_observations.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"

namespace fvm::workflows {
namespace {

TEST(ModelChoice, NamesAndSizesOfThePublishedModelsAndOfComposedOnes) {
  EXPECT_EQ((ModelChoice{"9", ""}.Layout().NumFree()), 9);
  EXPECT_EQ((ModelChoice{"42", ""}.Layout().NumFree()), 42);
  const ModelChoice own{"27", "xTx:legendre:2,yRz:1"};
  EXPECT_EQ(own.Name(), "terms:xTx:legendre:2,yRz:1");
  EXPECT_EQ(own.Layout().NumFree(), 3 + 2);  // xTx orders 0-2, yRz orders 0-1
}

TEST(ModelChoice, AModelThatIsNotOneIsRefusedAsInputNamingIt) {
  try {
    ModelChoice{"27", "qTq:1"}.Layout();
    FAIL() << "an unknown term was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("qTq"), std::string::npos) << e.what();
  }
}

// The job explains a simulated stage of 125 um mean error down to the noise: 0.5 um per coordinate in each of
// the two exports leaves sqrt(6) x 0.5 = 1.22 um rms of the 3-D residual, less the share the fit takes (about
// 15 of 3 x 136 components). Bounds 0.9-1.3 um hold that with room for the sampling spread of 136 centres.
TEST(IdentifyModel, ExplainsTheSimulatedStageDownToTheNoise) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 3;
  sim.truth_model = "15";
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  const stage::MeasurementSet set = artefacts::Observations(batch.batch, batch.batch.identify);
  const stage::IdentificationResult r = IdentifyModel({"15", ""}, set, IdentifySettings{});
  EXPECT_EQ(r.calibration.model, "15");
  ASSERT_TRUE(r.converged);
  EXPECT_GT(r.residual_summary.rms_um(), 0.9);
  EXPECT_LT(r.residual_summary.rms_um(), 1.3);
  // A bar cannot tell every coefficient of the 15 model: the rest are fixed and named.
  EXPECT_EQ(r.calibration.layout.NumFree() + static_cast<int>(r.fixed.size()), 15);
}

}  // namespace
}  // namespace fvm::workflows
