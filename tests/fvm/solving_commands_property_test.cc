// fvm calibrate, compare, diagnose, correct and calibrate --scan under a seeded stream of structured mutations of
// their files (issue 44, extending issue 34's machine commands): subnormal, huge and NaN-text numbers, empty
// fields, a whole column of them, gross outliers, and the row and column mutations of MutateCsv. Whatever the
// input, the contract holds: no signal, an exit code of 0 to 3, a refusal that says why and leaves nothing behind,
// nothing written or printed with nan or inf in it, and no NaN past the readers (the guarded decompositions'
// message in a refusal means a reader let one through).
//
// The count per command is FVM_MUTATIONS_PER_COMMAND (default 12, to keep ctest fast); the issue's acceptance run is
//   FVM_MUTATIONS_PER_COMMAND=200 build/tests/fvm/solving_commands_property_tests

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "tests/fvm/mutation_support.h"
#include "tests/support/run_fvm.h"
#include "tests/support/test_support.h"

namespace fvm::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

int MutationsPerCommand() {
  const char* text = std::getenv("FVM_MUTATIONS_PER_COMMAND");
  const int n = text ? std::atoi(text) : 0;
  return n > 0 ? n : 12;
}

// The inputs every command starts from, made once: the sample batch, its calibration, simulated scans.
class SolvingCommands : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const std::string d = dir_->path().string();
    ASSERT_EQ(RunFvm(*dir_, "simulate fvm-batch -o " + d + "/batch --seed 1").status, 0);
    // Two validation placements of the ten: the same code paths, a fraction of the time.
    for (const auto& entry : fs::directory_iterator(*dir_ / "batch")) {
      const std::string name = entry.path().filename().string();
      if (name.starts_with("val-") && !name.starts_with("val-01.") && !name.starts_with("val-02.")) fs::remove(entry.path());
    }
    std::ofstream(*dir_ / "batch/batch.json")
        << R"({"identify": ["id-x", "id-y", "id-oblique"], "validate": ["val-01", "val-02"], "lens": "5x"})";
    ASSERT_EQ(RunFvm(*dir_, "calibrate " + d + "/batch --model 15 -o " + d + "/cal.json").status, 0);
    ASSERT_EQ(RunFvm(*dir_, "simulate scan -o " + d + "/scan --seed 1 --tile-px 128 --length-mm 30 --validation 5").status, 0);
    const std::string truth = ReadText(*dir_ / "scan/truth.json");
    const size_t at = truth.find("\"pixel_mm\"");
    ASSERT_NE(at, std::string::npos);
    pixel_mm_ = truth.substr(truth.find(':', at) + 1);
    pixel_mm_ = pixel_mm_.substr(0, pixel_mm_.find_first_of(",}\n"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static TempDir* dir_;
  static std::string pixel_mm_;
};
TempDir* SolvingCommands::dir_ = nullptr;
std::string SolvingCommands::pixel_mm_;

std::vector<fs::path> CsvFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".csv") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST_P(SolvingCommands, NoSignalNoHalfOutputNoNonFiniteNumbers) {
  const std::string command = GetParam();
  const TempDir& dir = *dir_;
  const std::string d = dir.path().string();
  std::mt19937_64 random(44 + std::hash<std::string>{}(command) % 1000);
  const auto pick = [&](size_t n) { return static_cast<size_t>(random() % n); };
  const int count = MutationsPerCommand();
  int refused = 0;
  for (int iteration = 0; iteration < count; ++iteration) {
    const fs::path out = dir / ("out-" + command);
    fs::remove_all(out);
    fs::create_directories(out);
    // The file to mutate and the command line reading it.
    fs::path source, target;
    std::string arguments, output;
    if (command == "correct") {
      source = dir / "batch/val-01.free.csv";
      target = out / "in.csv";
      output = (out / "corrected.csv").string();
      arguments = "correct --calibration " + d + "/cal.json " + target.string() + " -o " + output + " --json";
    } else if (command == "scan") {
      const std::vector<std::string> layouts = {"row", "column", "diagonal"};
      const std::string mutated = layouts[pick(layouts.size())];
      source = dir / ("scan/" + mutated + ".csv");
      target = dir / ("scan/mutated-" + mutated + ".csv");  // beside the tiles its rows name
      output = (out / "cal.json").string();
      arguments = "calibrate --pixel-mm " + pixel_mm_ + " --model 15 --json -o " + output;
      for (const std::string& l : layouts) {
        arguments += " --scan " + (l == mutated ? target.string() : d + "/scan/" + l + ".csv");
      }
    } else {
      fs::copy(dir / "batch", out / "batch");
      const std::vector<fs::path> files = CsvFiles(out / "batch");
      source = files[pick(files.size())];
      target = source;
      const std::string batch = (out / "batch").string();
      if (command == "calibrate") {
        output = (out / "cal.json").string();
        arguments = "calibrate " + batch + " --model 15 --json -o " + output;
      } else if (command == "compare") {
        arguments = "compare " + batch + " --models 9,15 --json";
      } else {
        arguments = "diagnose " + batch + " --model 15 --json";
      }
    }
    const std::string original = ReadText(source);
    std::ofstream(target, std::ios::trunc) << (pick(4) != 0 ? MutateNumbers(original, random) : MutateCsv(original, random));
    const FvmRun run = RunFvm(dir, arguments);
    const std::string what = "fvm " + arguments + "\nmutated " + target.string() + ":\n" + ReadText(target) +
                             "\nstderr: " + run.err;
    if (std::getenv("FVM_PROPERTY_VERBOSE")) {
      std::printf("%s %d: %s\n", command.c_str(), run.status, run.err.substr(0, run.err.find('\n')).c_str());
    }
    ASSERT_GE(run.status, 0) << "killed by a signal: " << what;
    ASSERT_LE(run.status, 3) << what;
    if (run.status == 1 || run.status == 2) {
      ++refused;
      EXPECT_FALSE(run.err.empty()) << "refused without a word: " << what;
      EXPECT_THAT(run.err, Not(HasSubstr("matrix to decompose"))) << "a non-finite number got past the readers: " << what;
      if (!output.empty()) {
        EXPECT_FALSE(fs::exists(output)) << "written although refused: " << what;
      }
    } else {
      EXPECT_FALSE(HoldsNonFinite(run.out)) << "nan or inf printed: " << what << "\nstdout: " << run.out;
      if (!output.empty()) {
        EXPECT_FALSE(HoldsNonFinite(FilesText(output))) << "nan or inf written: " << what;
      }
    }
  }
  // Most mutations are refused (subnormal, nan, empty cells, a duplicated id); some are fine (an outlier, a row
  // gone), and a long run must see both.
  if (count >= 10) {
    EXPECT_GT(refused, 0) << command;
  }
  if (count >= 50) {
    EXPECT_LT(refused, count) << command;
  }
}

INSTANTIATE_TEST_SUITE_P(Commands, SolvingCommands,
                         ::testing::Values("calibrate", "compare", "diagnose", "correct", "scan"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace fvm::testing
