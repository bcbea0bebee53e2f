#include "workflows/compare_models.h"

#include <gtest/gtest.h>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"

namespace fvm::workflows {
namespace {

// A stage whose truth is the 27 model: the 15 model (constant terms, which a rigid fit per placement takes up
// anyway) cannot follow it, the 42 model follows it no better, so the comparison recommends 27, the simplest model
// within 10 % of the best after a rigid fit per held-out placement.
TEST(CompareModels, RecommendsTheSimplestModelThatFollowsTheStage) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 6;
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  std::vector<std::string> told;
  const ModelComparison c = CompareModels(batch.batch, {"15", "27", "42"}, {}, [&](const std::string& m) { told.push_back(m); });
  EXPECT_EQ(told, (std::vector<std::string>{"15", "27", "42"}));
  ASSERT_EQ(c.scores.size(), 3u);
  EXPECT_TRUE(c.validation_placements);
  EXPECT_EQ(c.scores[1].nominal, 27);
  EXPECT_GT(c.scores[0].rigid.rms_mm, 2.0 * c.scores[1].rigid.rms_mm);  // the 15 model misses the truth's slopes
  EXPECT_LE(c.scores[1].rigid.rms_mm, 1.1 * c.scores[2].rigid.rms_mm);
  EXPECT_EQ(c.recommendation.rfind("Use model 27:", 0), 0u) << c.recommendation;
  EXPECT_EQ(c.scores[1].validation.count, static_cast<int>(17 * batch.batch.validate.size()));
}

// Without validation placements each identification placement is left out in turn and judged by a model
// identified on the others: every centre of the batch is judged once.
TEST(CompareModels, LeavesEachPlacementOutWhenNoneAreHeldOut) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 6;
  artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  batch.batch.validate.clear();
  const ModelComparison c = CompareModels(batch.batch, {"27"}, {});
  EXPECT_FALSE(c.validation_placements);
  EXPECT_EQ(c.scores[0].validation.count, static_cast<int>(17 * batch.batch.identify.size()));
  EXPECT_NE(c.recommendation.find("placements left out in turn"), std::string::npos) << c.recommendation;

  // The summary: the --json document without the batch's path, the table naming it, no report.
  CompareOptions options;
  options.models = {"27"};
  const Summary summary = Summarize(c, options, "my-batch");
  EXPECT_EQ(summary.json["validation_by"], "leave-one-placement-out");
  EXPECT_EQ(summary.json["models"][0]["validation"]["centres"].get<int>(), c.scores[0].validation.count);
  EXPECT_EQ(summary.json["models"][0]["validation"]["rigid"]["rms_um"].get<double>(), c.scores[0].rigid.rms_mm * 1e3);
  EXPECT_EQ(summary.json["recommendation"], c.recommendation);
  EXPECT_FALSE(summary.json.contains("batch"));
  EXPECT_EQ(summary.text.rfind("fvm compare: my-batch (validation: leave-one-placement-out)\n", 0), 0u) << summary.text;
  EXPECT_NE(summary.text.find("\n  " + c.recommendation + "\n"), std::string::npos);
  EXPECT_FALSE(summary.report.has_value());
}

// Options are checked naming the command line's spelling.
TEST(CompareModels, OptionsNameTheCommandLinesOption) {
  CompareOptions options;
  EXPECT_NO_THROW(options.Check());
  options.models = {"27", "28"};
  EXPECT_THROW(options.Check(), InputError);
  options.models.clear();
  EXPECT_THROW(options.Check(), InputError);
  options.models = {"27"};
  options.settings.anchor = "last-tile";
  try {
    options.Check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--anchor: 'last-tile'", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace fvm::workflows
