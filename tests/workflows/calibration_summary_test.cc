// The summary of `fvm calibrate` built by the library (workflows/calibration_summary.h): the JSON document, the
// printed table and the report's data come from the run's figures, for the batch and the scan route alike, and the
// options refuse what the command line refuses, naming the option.

#include "workflows/calibration_summary.h"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <variant>

#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "artefacts/simulation/stage_truth.h"
#include "core/input_error.h"
#include "imaging/tile_plan.h"

namespace fvm::workflows {
namespace {

artefacts::SimulatedFvmBatch SummaryBatch(unsigned seed) {
  artefacts::FvmBatchOptions sim;
  sim.seed = seed;
  return artefacts::SimulateFvmBatch(sim);
}

bool TextHas(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(CalibrationSummary, BatchDocumentTextAndReportShowTheRunsFigures) {
  const artefacts::SimulatedFvmBatch sim = SummaryBatch(4);
  const BatchCalibrationRun run = CalibrateBatchInput({"sim", sim.batch, std::nullopt}, {});
  const Summary s = Summarize(run);
  const BeforeAfter& judged = *run.calibration.judged;
  EXPECT_EQ(s.json["batch"], "sim");
  EXPECT_EQ(s.json["anchor"], "none");
  EXPECT_EQ(s.json["model"], "27");
  EXPECT_EQ(s.json["identification"]["placements"], sim.batch.identify);
  EXPECT_EQ(s.json["validation"]["placements"], sim.batch.validate);
  EXPECT_EQ(s.json["validation"]["rigid"]["rms_um"].get<double>(), judged.after.rigid.rms_mm * 1e3);
  EXPECT_EQ(s.json["validation"]["before"]["distances"]["count"].get<int>(), judged.before.distances.count);
  EXPECT_FALSE(s.json.contains("raw_exports"));
  EXPECT_EQ(s.text.rfind("fvm calibrate: model 27 (YXFZ chain, eq. 1) on sim\n", 0), 0u) << s.text;
  EXPECT_TRUE(TextHas(s.text, "  validation, " + std::to_string(judged.after.first_tile.count) + " centres;")) << s.text;
  EXPECT_TRUE(TextHas(s.text, "largest distance error on validation")) << s.text;
  EXPECT_EQ(s.text.back(), '\n');
  ASSERT_TRUE(s.report.has_value());
  const auto& data = std::get<report::ReportData>(*s.report);
  EXPECT_EQ(data.title, "fvm calibrate: model 27 on sim");
  EXPECT_EQ(data.errors_after.size(), run.calibration.validation->observations.size());
  EXPECT_EQ(data.parameters.size(), static_cast<size_t>(run.calibration.result.calibration.layout.NumFree()));
}

// Without validation placements: no validation block; a report only when the identification ones were judged.
TEST(CalibrationSummary, BatchWithoutHeldOutPlacementsHasNoValidationBlock) {
  artefacts::SimulatedFvmBatch sim = SummaryBatch(4);
  sim.batch.validate.clear();
  CalibrateJobOptions options;
  Summary s = Summarize(CalibrateBatchInput({"sim", sim.batch, std::nullopt}, options));
  EXPECT_FALSE(s.json.contains("validation"));
  EXPECT_FALSE(TextHas(s.text, "validation"));
  EXPECT_FALSE(s.report.has_value());
  options.judge_identification = true;
  s = Summarize(CalibrateBatchInput({"sim", sim.batch, std::nullopt}, options));
  EXPECT_FALSE(s.json.contains("validation"));
  ASSERT_TRUE(s.report.has_value());
  EXPECT_EQ(std::get<report::ReportData>(*s.report).summary.at(4).second, "identification placements");
}

// 30 mm paths of 128 px tiles (the 5x lens' field): seconds, every pair registered.
TEST(CalibrationSummary, ScanDocumentAndTextShowTheRegistrationsAndThePrediction) {
  const artefacts::SimulatedFvmBatch sim = SummaryBatch(4);
  const artefacts::StageTruth truth{sim.truth.layout, sim.truth.values, 0.0, 25.0};
  imaging::CalibrationScanOptions plan;
  plan.length_mm = 30.0;
  imaging::TilePlanOptions lens;
  lens.fov_mm = 2.82;
  lens.overlap = 0.25;
  artefacts::ScanSimulationOptions render;
  render.tile_px = 128;
  render.pixel_mm = lens.fov_mm / render.tile_px;
  std::vector<artefacts::RegisteredScan> scans;
  for (const auto& scan : artefacts::SimulateScans(truth, imaging::PlanCalibrationScans(plan, lens), render)) {
    scans.push_back(artefacts::RegisterScan(scan.name, scan.encoder_mm, scan.images, render.pixel_mm, false));
  }
  CalibrateJobOptions options;
  options.model.model = "15";
  options.pixel_mm = render.pixel_mm;
  options.validate = "bar";
  ScanCalibrationResult r = CalibrateScans(scans, {options.model, options.settings, options.pixel_mm, 0.0}, &sim.batch);
  const double combined = r.predicted_xy_with_misfit_um;
  const ScanCalibrationRun run{options, {"row.csv", "column.csv", "diagonal.csv"}, scans, std::nullopt, std::move(r)};
  const Summary s = Summarize(run);
  ASSERT_EQ(s.json["scans"].size(), 3u);
  EXPECT_EQ(s.json["scans"][0]["registered"], s.json["scans"][0]["pairs"]);
  EXPECT_EQ(s.json["predicted_xy_u_um"]["combined"].get<double>(), combined);
  EXPECT_EQ(s.json["pixel_mm"].get<double>(), render.pixel_mm);
  EXPECT_EQ(s.json["validation"]["batch"], "bar");
  EXPECT_FALSE(s.json.contains("distortion"));
  EXPECT_EQ(s.text.rfind("fvm calibrate: model 15 (YXFZ chain, eq. 1) on 3 scans (row.csv, column.csv, diagonal.csv)\n", 0), 0u)
      << s.text;
  EXPECT_TRUE(TextHas(s.text, fmt::format("  {}: {} tiles", scans[0].name, scans[0].encoder_mm.size()))) << s.text;
  EXPECT_TRUE(TextHas(s.text, "grey tiles show no heights")) << s.text;
  ASSERT_TRUE(s.report.has_value());
  EXPECT_EQ(std::get<report::ReportData>(*s.report).summary.at(4).second, "validation placements of bar");
}

TEST(CalibrateJobOptions, ScanOptionsAreRefusedByTheirNames) {
  CalibrateJobOptions options;
  const auto refusal = [&options] {
    try {
      options.CheckScans();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_TRUE(TextHas(refusal(), "--scan needs --pixel-mm"));
  options.pixel_mm = 0.00275;
  EXPECT_EQ(refusal(), "");
  options.pixel_u_mm = -1.0;
  EXPECT_TRUE(TextHas(refusal(), "--pixel-u-mm"));
  options.pixel_u_mm = 0.0;
  options.distortion.identify = true;
  options.distortion.order = "9";
  EXPECT_TRUE(TextHas(refusal(), "--distortion 9: give the polynomial order 2..")) << refusal();
  options.distortion.order = "";
  options.distortion.file = "field.json";
  EXPECT_TRUE(TextHas(refusal(), "--distortion and --distortion-file")) << refusal();
  options.distortion = {};
  options.distortion.save = "field.json";
  EXPECT_TRUE(TextHas(refusal(), "--save-distortion field.json: there is no field to save")) << refusal();
}

}  // namespace
}  // namespace fvm::workflows
