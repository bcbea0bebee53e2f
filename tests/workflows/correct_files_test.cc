#include "workflows/correct_files.h"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <optional>

#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "core/input_error.h"
#include "stage/io/calibration_file.h"
#include "tests/support/test_support.h"
#include "workflows/correct.h"

namespace fvm::workflows {
namespace {

// The simulator's true model, written as `fvm calibrate -o` writes a calibration (zero covariance).
class CorrectFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    artefacts::FvmBatchOptions sim;
    sim.seed = 3;
    const artefacts::SimulatedFvmBatch batch = artefacts::SimulateFvmBatch(sim);
    const int n = batch.truth.layout.NumFree();
    truth_.emplace(stage::Calibration{"27", batch.truth.layout, batch.truth.values, Eigen::MatrixXd::Zero(n, n), 0.0, std::nullopt, {}});
    calibration_ = dir_.Write("cal.json", stage::CalibrationToJson(stage::IdentificationResult(*truth_)).dump(2));
    const artefacts::Placement& p = batch.exact.Get(batch.exact.validate.front());
    for (size_t i = 0; i < p.ids.size(); ++i) free_.centres.push_back({p.ids[i], p.free[i], std::nullopt, std::nullopt, std::nullopt, std::nullopt});
    artefacts::WriteCentreExport(dir_ / "val.free.csv", free_);
  }

  CorrectOptions Options(const std::string& input, const std::string& output) const {
    CorrectOptions o;
    o.calibration = calibration_.string();
    o.input = (dir_ / input).string();
    o.output = (dir_ / output).string();
    o.version = "test";
    return o;
  }

  testing::TempDir dir_;
  std::optional<stage::Calibration> truth_;
  std::filesystem::path calibration_;
  artefacts::CentreExport free_;
};

// A centre export (a .csv naming an id column) is corrected as CorrectCentres corrects it; the summary names the
// output path for the front end to add, and its JSON holds the corrected centres.
TEST_F(CorrectFiles, ACentreExportIsCorrectedAsCorrectCentresDoes) {
  CorrectOptions o = Options("val.free.csv", "val.corrected.csv");
  o.frame = "first-tile";
  const CorrectedFiles out = workflows::CorrectFiles(o);
  const CentreCorrection expected = CorrectCentres(*truth_, free_, stage::StitchedFrame::kRotated, o.input);
  ASSERT_EQ(out.summary.json["centres"].size(), expected.centres.size());
  for (size_t i = 0; i < expected.centres.size(); ++i) {
    EXPECT_EQ(out.summary.json["centres"][i]["id"].get<int>(), free_.centres[i].id);
    // The export holds 6 decimals of mm: the centres read back differ from the ones in memory by up to 0.5 nm.
    EXPECT_NEAR(out.summary.json["centres"][i]["x"].get<double>(), expected.centres[i].position.x(), 1e-6);
  }
  EXPECT_EQ(out.summary.json["frame"], "first-tile");
  EXPECT_FALSE(out.summary.json.contains("output"));
  ASSERT_EQ(out.paths.size(), 1u);
  EXPECT_EQ(out.paths[0], std::make_pair(std::string("output"), o.output));
  EXPECT_EQ(out.summary.text.rfind(fmt::format("corrected {} centres of {} with model 27 in the first-tile frame", free_.centres.size(), o.input), 0), 0u)
      << out.summary.text;
  const artefacts::CentreExport written = artefacts::ReadCentreExport(o.output);
  ASSERT_EQ(written.centres.size(), free_.centres.size());
  EXPECT_NEAR(written.centres[0].position.x(), expected.centres[0].position.x(), 5e-7);  // 6 decimals of mm
}

// The same points as an XYZ cloud are a scan: corrected point by point, each exactly as the centre there (1 nm: the
// file's 6 decimals).
TEST_F(CorrectFiles, AnXyzCloudIsAScanCorrectedPointByPoint) {
  std::string xyz;
  for (const artefacts::CentreRecord& c : free_.centres) xyz += fmt::format("{:.6f} {:.6f} {:.6f}\n", c.position.x(), c.position.y(), c.position.z());
  dir_.Write("points.xyz", xyz);
  EXPECT_FALSE(artefacts::IsCentreExportFile(dir_ / "points.xyz"));
  EXPECT_TRUE(artefacts::IsCentreExportFile(dir_ / "val.free.csv"));
  const CorrectedFiles out = workflows::CorrectFiles(Options("points.xyz", "points.out.xyz"));
  EXPECT_EQ(out.summary.json["corrected"].get<size_t>(), free_.centres.size());
  EXPECT_EQ(out.summary.json["frame"], "stage");
  ASSERT_EQ(out.paths.size(), 2u);
  EXPECT_EQ(out.paths[0].first, "input");
  const CentreCorrection centres = CorrectCentres(*truth_, free_, std::nullopt, "centres");
  EXPECT_NEAR(out.summary.json["largest_shift_um"].get<double>(), centres.largest_shift_mm * 1e3, 1e-3);
}

// A machine model is told by what it names; bad options are refused naming the option as the command line spells it.
TEST_F(CorrectFiles, SniffsMachineModelsAndChecksItsOptions) {
  EXPECT_FALSE(stage::IsMachineModelFile(calibration_));
  EXPECT_TRUE(stage::IsMachineModelFile(dir_.Write("machine.json", R"({"model": "x", "instrument_pose": {}})")));
  EXPECT_FALSE(stage::IsMachineModelFile(dir_.Write("broken.json", "{")));
  CorrectOptions o = Options("val.free.csv", "x.csv");
  o.frame = "tile";
  try {
    workflows::CorrectFiles(o);
    FAIL() << "a bad frame was taken";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--frame: 'tile'", 0), 0u) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.csv"));
  o = Options("", "x.csv");
  EXPECT_THROW(workflows::CorrectFiles(o), InputError);
}

}  // namespace
}  // namespace fvm::workflows
