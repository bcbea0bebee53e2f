// The stage a scan simulation runs on: read back from the truth.json that fvm simulate fvm-batch writes (the same
// coefficients, the same model), with the batch's summary equal to that file; and the refusals of a file that is
// not a truth.

#include "workflows/simulate_scan.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/input_error.h"
#include "tests/support/test_support.h"
#include "workflows/simulate_batch.h"

namespace fvm::workflows {
namespace {

TEST(ReadStageTruth, ReadsTheBatchTruthItsSimulatorWrote) {
  const fvm::testing::TempDir dir;
  SimulateBatchOptions options;
  options.batch.seed = 5;
  options.batch.truth_model = "15";
  options.batch.periodic_um = 0.4;
  options.batch.validation_placements = 1;
  const SimulatedBatch batch = SimulateBatch(options, dir.path());
  std::string model;
  const artefacts::StageTruth truth = ReadStageTruth((dir.path() / "truth.json").string(), &model);
  EXPECT_EQ(model, "15");
  EXPECT_EQ(truth.values, batch.simulation.truth.values);  // written with every digit
  EXPECT_EQ(truth.periodic_um, 0.4);
  std::ifstream file(dir.path() / "truth.json");
  EXPECT_EQ(Summarize(batch).json, nlohmann::ordered_json::parse(file));
}

TEST(ReadStageTruth, RefusesAFileThatIsNoTruthNamingIt) {
  const fvm::testing::TempDir dir;
  const auto refusal = [&](const std::string& text) {
    const std::string path = (dir.path() / "t.json").string();
    std::ofstream(path) << text;
    std::string model;
    try {
      ReadStageTruth(path, &model);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(R"({"seed": 1})").find("t.json: neither a calibration file nor a truth.json"), std::string::npos);
  EXPECT_NE(refusal(R"({"model": "9", "parameters": [{"name": "bogus", "value": 1}]})")
                .find("parameter 'bogus' is not a coefficient of model 9"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"model": "8", "parameters": []})").find("t.json: model: "), std::string::npos);
}

}  // namespace
}  // namespace fvm::workflows
