#include "workflows/diagnose.h"

#include <gtest/gtest.h>

#include "artefacts/simulation/fvm_batch_simulation.h"

namespace fvm::workflows {
namespace {

// A lens scale error of 300 ppm hidden in the stitched exports, which the 15 model cannot take: the workflow names
// it and the held-out placements confirm it (their mean error falls).
TEST(DiagnoseBatch, NamesAHiddenScaleAndTheHeldOutPlacementsConfirmIt) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 2;
  sim.truth_model = "15";
  sim.hidden_effect = "scale";
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  DiagnoseOptions options;
  options.model = {"15", ""};
  const BatchDiagnosis d = DiagnoseBatch(batch.batch, options);
  ASSERT_TRUE(d.diagnosis.effect.has_value());
  EXPECT_EQ(*d.diagnosis.effect, "scale");
  EXPECT_LT(d.diagnosis.validation_after.mean_mm, 0.5 * d.diagnosis.validation_before.mean_mm);
  EXPECT_EQ(d.identification.observations.size(), 17u * batch.batch.identify.size());
  EXPECT_EQ(d.validation.observations.size(), 17u * batch.batch.validate.size());
  // One distance per centre but the first of each placement, and the scale shows in them: 300 ppm of up to
  // 160 mm is up to 48 um before; after, the noise of two exports (under 5 um).
  ASSERT_EQ(d.distance_errors_before_mm.size(), 16u * batch.batch.identify.size());
  double before = 0, after = 0;
  for (double e : d.distance_errors_before_mm) before = std::max(before, std::abs(e));
  for (double e : d.distance_errors_after_mm) after = std::max(after, std::abs(e));
  EXPECT_GT(before * 1e3, 20.0);
  EXPECT_LT(after * 1e3, 5.0);

  // The summary: the JSON contract's keys, the text naming the batch, and the report's data (a step per effect).
  const Summary summary = Summarize(d, options, "scaled");
  EXPECT_EQ(summary.json["effect"], "scale");
  EXPECT_EQ(summary.json["effects"][0]["effect"], "scale");
  EXPECT_EQ(summary.json["after"]["mean_um"].get<double>(), d.diagnosis.after.mean_mm * 1e3);
  EXPECT_EQ(summary.json["model"], "15");
  EXPECT_FALSE(summary.json.contains("batch"));
  EXPECT_EQ(summary.text.rfind("fvm diagnose: model 15 on scaled (", 0), 0u) << summary.text;
  ASSERT_TRUE(summary.report.has_value());
  const auto& report = std::get<report::ReportData>(*summary.report);
  EXPECT_EQ(report.title, "fvm diagnose: model 15 on scaled");
  ASSERT_EQ(report.steps.size(), 1u + d.diagnosis.steps.size());
  EXPECT_EQ(report.steps[1].label.rfind("+ scale", 0), 0u);
  EXPECT_EQ(report.errors_before.size(), d.identification.observations.size());
}

// Three failed sphere fits (80 um) among the identification centres: flagged and taken out, so the residuals after
// belong to fewer centres and their distance errors are not paired with the wrong ones (left empty instead).
TEST(DiagnoseBatch, OutliersTakenOutLeaveNoMispairedDistanceErrors) {
  artefacts::FvmBatchOptions sim;
  sim.seed = 3;
  sim.hidden_effect = "outliers";
  const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
  const BatchDiagnosis d = DiagnoseBatch(batch.batch, {});
  ASSERT_TRUE(d.diagnosis.effect.has_value());
  EXPECT_EQ(*d.diagnosis.effect, "outliers");
  EXPECT_LT(d.diagnosis.residuals_after.size(), d.identification.observations.size());
  EXPECT_EQ(d.distance_errors_before_mm.size(), 16u * batch.batch.identify.size());
  EXPECT_TRUE(d.distance_errors_after_mm.empty());
}

}  // namespace
}  // namespace fvm::workflows
