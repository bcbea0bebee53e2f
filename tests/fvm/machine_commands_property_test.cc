// fvm verify, uncertainty, multilaterate and testpiece verify under a seeded stream of structured mutations of
// their options and files (issue 34): absurd numbers in every numeric option, lists of the wrong length, cells
// turned to nan or 1e308, rows dropped, repeated or made equal, columns swapped, a file cut short. Whatever the
// input, the contract holds: no signal, an exit code of 0 to 3, nothing written on a refusal, and nothing written
// or printed with nan or inf in it.

#include <gtest/gtest.h>

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

struct Command {
  std::string name;    // for messages
  std::string prefix;  // the command and its required options; @DATA@ is the (possibly mutated) main file
  std::string data;    // the main file
  std::vector<std::pair<std::string, std::vector<std::string>>> options;  // flag, sensible values
  std::string output;  // what a refused run must not leave behind ("" when it prints only)
};

TEST(MachineCommandsProperty, NoSignalNoHalfOutputNoNonFiniteNumbers) {
  TempDir dir;
  const std::string d = dir.path().string();
  // The inputs: a simulated machine read by a tracker, the same by four stations, a test piece on a CMM.
  std::ofstream(dir / "stations.json") << R"({"stations": [{"name": "A", "x": 1250, "y": -1699, "z": -1132},
    {"name": "B", "x": 3371, "y": 1975, "z": -1132}, {"name": "C", "x": -871, "y": 1975, "z": -1132},
    {"name": "D", "x": -1309, "y": -727, "z": 1121}]})";
  ASSERT_EQ(RunFvm(dir, "simulate tracker -o " + d + "/plan --seed 1 --tool 0,0,100 --points mesh:625,500,400").status, 0);
  ASSERT_EQ(RunFvm(dir, "simulate tracker -o " + d + "/net --seed 1 --tool 0,0,100 --points mesh:625,500,400 --stations " + d +
                            "/stations.json").status, 0);
  ASSERT_EQ(RunFvm(dir, "simulate testpiece -o " + d + "/tp --seed 1 --points series").status, 0);

  const std::vector<std::string> machine_values = {"2500x1500x1200", "3000x2000x1500@-100,-100,-100"};
  const std::vector<Command> commands = {
      {"verify", "verify @DATA@ --tool 0,0,100 --order 2 -o " + d + "/out/machine.json", d + "/plan/readings.csv",
       {{"--machine", machine_values}, {"--tool", {"0,0,100"}}, {"--pose", {"1100,-1000,600,63,14,35"}}, {"--order", {"1", "2"}}},
       d + "/out/machine.json"},
      {"uncertainty", "uncertainty @DATA@ --tool 0,0,100 --order 2 --runs 3 --json", d + "/plan/readings.csv",
       {{"--machine", machine_values}, {"--runs", {"2", "4"}}, {"--k", {"2"}}, {"--u-cal-um", {"1"}}, {"--temperature-c", {"0.5"}},
        {"--cte-per-k", {"11.5e-6"}}, {"--seed", {"3"}}, {"--order", {"1"}}},
       ""},
      {"multilaterate", "multilaterate @DATA@ --stations " + d + "/net/stations.json -o " + d + "/out/points.csv",
       d + "/net/readings.csv", {{"--tracker", {"published"}}}, d + "/out/points.csv"},
      {"testpiece verify", "testpiece verify @DATA@ --order 1 --json", d + "/tp/measured.csv",
       {{"--order", {"1", "2"}}, {"--tool", {"0,0,100"}}, {"--machine", {"400x400x300@-200,-200,-100"}}},
       ""},
  };

  std::mt19937_64 random(34);
  const auto pick = [&](size_t n) { return static_cast<size_t>(random() % n); };
  int runs = 0, refused = 0;
  for (int iteration = 0; iteration < 40; ++iteration) {
    const Command& c = commands[static_cast<size_t>(iteration) % commands.size()];
    fs::remove_all(dir / "out");
    fs::create_directories(dir / "out");
    std::string data = c.data;
    std::string args;
    // Half the runs mutate the file, half an option; a quarter both.
    const bool mutate_file = iteration % 2 == 0 || pick(4) == 0;
    if (mutate_file) {
      data = d + "/out/data.csv";
      std::ofstream(data) << MutateCsv(ReadText(c.data), random);
    }
    for (const auto& [flag, sensible] : c.options) {
      if (pick(3) != 0) continue;
      std::string value = sensible[pick(sensible.size())];
      if (!mutate_file || pick(2) == 0) {
        // An absurd number in place of one of the value's numbers, or the whole value.
        const std::string absurd = kAbsurd[pick(kAbsurd.size())];
        const std::vector<std::string> parts = Cells(value);
        value = parts.size() > 1 && pick(2) ? Join({absurd}, "") + value.substr(parts[0].size()) : absurd;
      }
      args += " " + flag + "='" + value + "'";
    }
    std::string prefix = c.prefix;
    prefix.replace(prefix.find("@DATA@"), 6, data);
    const FvmRun run = RunFvm(dir, prefix + args);
    ++runs;
    const std::string what = "fvm " + prefix + args + "\nstderr: " + run.err;
    ASSERT_GE(run.status, 0) << "killed by a signal: " << what;
    ASSERT_LE(run.status, 3) << what;
    if (run.status == 1 || run.status == 2) {
      ++refused;
      EXPECT_FALSE(run.err.empty()) << "refused without a word: " << what;
      if (!c.output.empty()) {
        EXPECT_FALSE(fs::exists(c.output)) << "written although refused: " << what;
      }
    } else {
      EXPECT_FALSE(HoldsNonFinite(run.out)) << "nan or inf printed: " << what << "\nstdout: " << run.out;
      if (!c.output.empty()) {
        EXPECT_FALSE(HoldsNonFinite(FilesText(c.output))) << "nan or inf written: " << what;
      }
    }
  }
  // The stream must reach both sides of the contract, or it tests nothing.
  EXPECT_GT(refused, runs / 4);
  EXPECT_LT(refused, runs);
}

}  // namespace
}  // namespace fvm::testing
