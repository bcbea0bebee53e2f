// The calibration JSON: what `fvm calibrate` writes, `fvm correct` reads back exactly, and a hand-edited file
// that no longer describes a valid model is refused with an InputError naming the file and the key.

#include "stage/io/calibration_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <unistd.h>

#include "core/input_error.h"
#include "stage/calibration.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;

// A small model with every coefficient state: free, fixed, tied.
IdentificationResult SmallResult() {
  ParameterLayout layout(AxisChain::FvmStage(), testing::FvmTravel());
  layout.SetTerm("xTx", Basis::kPower, 1);
  layout.SetTerm("yTx", Basis::kLegendre, 0);
  layout.SetTerm("yRz", Basis::kPower, 0);
  layout.SetTerm("xWy", Basis::kPower, 0);
  layout.Fix("xTx1", 0.002);
  layout.Tie("yTx0", "xTx0", -0.5);
  // Free: xTx0, yRz0, xWy.
  Calibration cal{"terms:test", layout, {0.0125, 3.5e-5, -1.25e-4}, Eigen::MatrixXd::Zero(3, 3), 4e-4, Eigen::Vector3d(-185.0, -15.0, -50.0), {}};
  cal.covariance << 4e-8, 1e-12, 0, 1e-12, 9e-12, 2e-13, 0, 2e-13, 1.6e-11;
  IdentificationResult result(cal);
  result.residual_summary.rms_mm = 1.25e-3;
  result.converged = true;
  return result;
}

class CalibrationFile : public ::testing::Test {
 protected:
  static constexpr const char* kPlaceholder = "12345.5";
  std::filesystem::path Write(const json& doc) {
    std::ofstream(path_) << doc.dump(1);
    return path_;
  }
  // Edits the written calibration and expects ReadCalibration to refuse it with a message containing each of
  // `expected` (the file name and the key).
  void ExpectRefused(const std::function<void(json&)>& edit, const std::vector<std::string>& expected,
                     const std::string& infinity_text = "") {
    json doc = CalibrationToJson(SmallResult());
    edit(doc);
    std::string text = doc.dump(1);
    // JSON has no infinity (nlohmann writes null): a hand edit writes a number that overflows a double.
    if (!infinity_text.empty()) text.replace(text.find(kPlaceholder), std::string(kPlaceholder).size(), infinity_text);
    std::ofstream(path_) << text;
    try {
      ReadCalibration(path_);
      ADD_FAILURE() << "accepted: " << doc.dump();
    } catch (const InputError& e) {
      for (const std::string& part : expected) EXPECT_THAT(e.what(), HasSubstr(part));
      EXPECT_THAT(e.what(), HasSubstr(path_.string()));
    }
  }
  json& Parameter(json& doc, const std::string& name) {
    for (json& p : doc["parameters"]) {
      if (p["name"] == name) return p;
    }
    throw std::logic_error("no parameter " + name);
  }

  std::filesystem::path path_ = std::filesystem::temp_directory_path() /
                                ("fvm_calibration_file_test_" + std::to_string(::getpid()) + ".json");
  void TearDown() override { std::filesystem::remove(path_); }
};

TEST_F(CalibrationFile, RoundTripsEveryStateValueAndTheCovariance) {
  const IdentificationResult written = SmallResult();
  const Calibration read = ReadCalibration(Write(CalibrationToJson(written)));
  const Calibration& cal = written.calibration;
  EXPECT_EQ(read.model, "terms:test");
  EXPECT_EQ(read.layout.FreeNames(), cal.layout.FreeNames());
  ASSERT_EQ(read.layout.coefficients().size(), cal.layout.coefficients().size());
  for (size_t i = 0; i < cal.layout.coefficients().size(); ++i) {
    const auto& a = cal.layout.coefficients()[i];
    const auto& b = read.layout.coefficients()[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.state, b.state) << a.name;
    EXPECT_EQ(a.value, b.value) << a.name;  // JSON numbers round-trip doubles exactly
    EXPECT_EQ(a.tied_to, b.tied_to) << a.name;
  }
  EXPECT_EQ(read.layout.term(*FindErrorTerm("yTx")).basis, Basis::kLegendre);
  EXPECT_EQ(read.values, cal.values);
  EXPECT_EQ(read.covariance, cal.covariance);
  EXPECT_EQ(read.sigma_mm, cal.sigma_mm);
  EXPECT_EQ(read.frame_reference, cal.frame_reference);  // the first tile whose view the part frame is
  // The rebuilt model moves a point exactly as the written one.
  const Eigen::Vector3d q(-120, -35, -50);
  EXPECT_EQ(Forward(read.layout, read.values, q), Forward(cal.layout, cal.values, q));
}

TEST_F(CalibrationFile, RefusesAnUnknownCoefficient) {
  ExpectRefused([&](json& d) { Parameter(d, "yRz0")["name"] = "yRq0"; }, {"'parameters'[", "yRq0", "no such coefficient"});
  ExpectRefused([&](json& d) { Parameter(d, "xTx1")["name"] = "xTx7"; }, {"xTx7"});
}

TEST_F(CalibrationFile, RefusesATieToATiedCoefficientInsteadOfOverflowing) {
  // xTx0 is followed by yTx0; tying xTx0 to yRz0 used to leave yTx0 without a slot (heap overflow in Expand).
  ExpectRefused(
      [&](json& d) {
        json& p = Parameter(d, "xTx0");
        p["state"] = "tied";
        p["tied_to"] = "yRz0";
        p["factor"] = 1.0;
      },
      // The file lists xTx0 before its follower yTx0, so the refusal comes at yTx0: a tie to a tied coefficient.
      {"(yTx0)", "xTx0 is itself tied to yRz0"});
  // A tie to a tied coefficient (a chain).
  ExpectRefused(
      [&](json& d) {
        json& p = Parameter(d, "xWy");
        p["state"] = "tied";
        p["tied_to"] = "yTx0";
        p["factor"] = 1.0;
      },
      {"(xWy)", "yTx0 is itself tied to xTx0"});
}

// What the model cannot take at a point (a scan calibration's misfit along its scans) is kept by the file and
// reaches every corrected point's u beside the coefficients' share: 0.4 um and 0.3 um in x and y here.
TEST_F(CalibrationFile, KeepsTheUnmodelledPartAndCorrectCarriesItInTheU) {
  IdentificationResult written = SmallResult();
  EXPECT_FALSE(CalibrationToJson(written).contains("unmodelled_mm"));  // nothing estimated it: not written
  const Eigen::Vector3d q(-120, -35, -50);
  const Eigen::Matrix3d coefficients = Correct(written.calibration, q).covariance;
  written.calibration.unmodelled_mm = Eigen::Vector3d(4e-4, 3e-4, 0.0);
  const Calibration read = ReadCalibration(Write(CalibrationToJson(written)));
  EXPECT_EQ(read.unmodelled_mm, written.calibration.unmodelled_mm);
  const Eigen::Matrix3d with = Correct(read, q).covariance;
  EXPECT_NEAR(with(0, 0) - coefficients(0, 0), 1.6e-7, 1e-18);
  EXPECT_NEAR(with(1, 1) - coefficients(1, 1), 9e-8, 1e-18);
  EXPECT_EQ(with(2, 2), coefficients(2, 2));
  const FirstTileCompensation first_tile(read, StitchedFrame::kRotated, Eigen::Vector3d(-185.0, -15.0, -50.0));
  EXPECT_GE(first_tile.Correct(q).covariance(0, 0), 1.6e-7);
}

TEST_F(CalibrationFile, RefusesABadUnmodelledPart) {
  ExpectRefused([&](json& d) { d["unmodelled_mm"] = {1e-4, 2e-4}; }, {"unmodelled_mm", "three numbers"});
  ExpectRefused([&](json& d) { d["unmodelled_mm"] = {1e-4, -2e-4, 0.0}; }, {"'unmodelled_mm'[1]", "standard deviation"});
}

TEST_F(CalibrationFile, RefusesABadFrameReference) {
  ExpectRefused([&](json& d) { d["frame_reference_mm"] = {1.0, 2.0}; }, {"frame_reference_mm", "three numbers"});
}

TEST_F(CalibrationFile, RefusesAWrongFormatKey) {
  ExpectRefused([&](json& d) { d["format"] = "fvm-calibration/0"; }, {"'format'", kCalibrationFormat});
}

TEST_F(CalibrationFile, RefusesValuesThatAreNotFiniteNumbers) {
  // JSON has no NaN: a NaN written by a tool becomes null, a hand edit may write a string or a number that
  // overflows (the parser refuses those; ReadCalibration checks finiteness again for other writers).
  ExpectRefused([&](json& d) { Parameter(d, "yRz0")["value"] = nullptr; }, {"malformed"});
  ExpectRefused([&](json& d) { Parameter(d, "yRz0")["value"] = "NaN"; }, {"malformed"});
  ExpectRefused([&](json& d) { Parameter(d, "xTx1")["value"] = 12345.5; }, {"overflow"}, "1e999");
  ExpectRefused([&](json& d) { Parameter(d, "yTx0")["factor"] = 12345.5; }, {"overflow"}, "-1e999");
}

TEST_F(CalibrationFile, RefusesACovarianceOfTheWrongSize) {
  ExpectRefused([&](json& d) { d["covariance"].erase(2); }, {"'covariance' has 2 rows for 3 free parameters"});
  ExpectRefused([&](json& d) { d["covariance"][1].push_back(0.0); }, {"'covariance' row 1 has 4 entries"});
  ExpectRefused([&](json& d) { d["covariance"][0].erase(0); }, {"'covariance' row 0 has 2 entries"});
}

TEST_F(CalibrationFile, WritesAndReadsTheToolOffsetOfAMachineModel) {
  // A stage model has none, and its file does not name one (files written before the key read as they did).
  EXPECT_FALSE(CalibrationToJson(SmallResult()).contains("tool_offset_mm"));
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(12.5, -3.25, 100);
  ParameterLayout layout(chain, {Travel{0, 2500}, Travel{0, 1500}, Travel{0, 1200}});
  layout.SetTerm("zRx", Basis::kLegendre, 1);
  IdentificationResult machine(Calibration{"machine", layout, {0, 2e-5}, Eigen::MatrixXd::Identity(2, 2) * 1e-12, 0, std::nullopt, {}});
  const json doc = CalibrationToJson(machine);
  EXPECT_EQ(doc.at("tool_offset_mm"), json({12.5, -3.25, 100.0}));
  const Calibration read = ReadCalibration(Write(doc));
  EXPECT_EQ(read.layout.chain().tool_offset, chain.tool_offset);
  // zRx acts on the tool offset: the rebuilt model moves the tool point as the written one.
  const Eigen::Vector3d q(100, 200, 900);
  EXPECT_EQ(Forward(read.layout, read.values, q), Forward(layout, machine.calibration.values, q));
}

TEST_F(CalibrationFile, RefusesABadToolOffset) {
  ExpectRefused([&](json& d) { d["tool_offset_mm"] = {0, 0}; }, {"'tool_offset_mm' must be three numbers"});
  ExpectRefused([&](json& d) { d["tool_offset_mm"] = "0,0,100"; }, {"'tool_offset_mm' must be three numbers"});
  ExpectRefused([&](json& d) { d["tool_offset_mm"] = {0, "x", 100}; }, {"'tool_offset_mm'[1]"});
  ExpectRefused([&](json& d) { d["tool_offset_mm"] = {0, 0, 12345.5}; }, {"overflow"}, "1e999");
  ExpectRefused([&](json& d) { d["tool_offset_mm"] = {0, 0, 2e5}; }, {"'tool_offset_mm'[2]", "100 m"});
}

}  // namespace
}  // namespace fvm::stage
