// The machine Monte Carlo against repeat measurements of a machine the project did not make: ../shared/bench's
// trackergen.py (written apart from this code, errors that are not polynomials with --truth rich, the published
// tracker noise) reads one machine again and again with fresh noise (--noise-seed); each repeat is verified as
// fvm verify --validate does, on the machine's noise-free validation mesh. The Monte Carlo from the first repeat
// alone must predict the mean and the spread of the repeats' validation mean errors. Skips where ../shared or
// Debian's python3-numpy and python3-scipy are absent.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "stage/monte_carlo.h"
#include "tests/support/test_support.h"
#include "workflows/machine_problem.h"
#include "workflows/uncertainty.h"

namespace fvm::workflows {
namespace {

const std::filesystem::path kTrackergenScript = std::filesystem::path(FVM_BENCH_DIR) / "trackergen.py";

bool TrackergenAvailable() {
  return std::filesystem::exists(kTrackergenScript) &&
         std::system("/usr/bin/python3 -c 'import numpy, scipy' >/dev/null 2>&1") == 0;
}

// trackergen.py's own main, in one Python process: DIR/validation.csv (the noise-free 250 x 250 x 200 mm mesh) and
// DIR/repeatK.csv for K in 1..repeats (--noise --noise-seed K), all of machine `seed` (--truth rich).
void GenerateTrackergen(const std::filesystem::path& dir, int seed, int repeats) {
  const std::string script =
      "import sys, io, contextlib\n"
      "sys.dont_write_bytecode = True  # nothing written beside the bench\n"
      "sys.path.insert(0, sys.argv[1]); import trackergen\n"
      "d, seed, n = sys.argv[2], sys.argv[3], int(sys.argv[4])\n"
      "jobs = [('validation.csv', ['--step', '250,250,200'])]"
      " + [('repeat%d.csv' % k, ['--noise', '--noise-seed', str(k)]) for k in range(1, n + 1)]\n"
      "for name, extra in jobs:\n"
      "    sys.argv = ['trackergen.py', d + '/' + name, '--seed', seed, '--truth', 'rich'] + extra\n"
      "    with contextlib.redirect_stdout(io.StringIO()): trackergen.main()\n";
  const std::string command = "/usr/bin/python3 -c \"" + script + "\" '" + kTrackergenScript.parent_path().string() + "' '" +
                              dir.string() + "' " + std::to_string(seed) + " " + std::to_string(repeats) + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
}

MachineProblem TrackergenProblem(const std::filesystem::path& readings, const std::filesystem::path& validation) {
  MachineProblemOptions o;
  o.data = readings.string();
  o.validate = validation.string();
  o.tools = {Eigen::Vector3d(0, 0, 100)};
  o.threads = 1;
  return LoadMachineProblem(o);
}

// bash ../shared/bench/check uncertainty in one process, with enough repeats to know their spread: 96 readings (the
// 500 x 500 x 400 mm mesh of a 2500 x 1500 x 1200 mm machine, machine seed 3) and 539 noise-free validation
// readings, order 1 with the tracker pose. 200 repeats give the observed spread to 1 / sqrt(2 x 199) = 5 %, 200 runs
// the predicted one likewise: bounds 0.8-1.25 for both ratios (the goal). The spread of a dozen repeats is
// no measure of this: trackergen's noise seeds 1-24 happen to give every machine a spread 0.65-0.9 of what 200
// repeats give (the noise does not depend on the machine seed). The Monte Carlo starts from repeat 4 (it depends on
// the starting repeat, whose noise is in its estimate of the field): there the former validation truth, the
// held-out residuals shrunk point by point with the reference's estimation error left in them, predicted a spread
// of 1.32 of the observed; 0.94 with one field power for every direction (stage/residual_field.h).
TEST(MachineUncertaintyIndependent, PredictsRepeatsOfATrackergenMachine) {
  if (!TrackergenAvailable()) GTEST_SKIP() << kTrackergenScript << " or python3-numpy/scipy absent (no ../shared)";
  fvm::testing::TempDir dir;
  constexpr int kRepeats = 200, kStart = 4;
  ASSERT_NO_FATAL_FAILURE(GenerateTrackergen(dir.path(), 3, kRepeats));
  const std::filesystem::path validation = dir.path() / "validation.csv";
  std::vector<double> observed;
  std::optional<MachineProblem> start;
  for (int k = 1; k <= kRepeats; ++k) {
    MachineProblem problem = TrackergenProblem(dir.path() / ("repeat" + std::to_string(k) + ".csv"), validation);
    const stage::VerificationResult verified = VerifyProblem(problem, problem.Layout(1));
    observed.push_back(JudgeOn(verified, problem.validation_observations, problem.options.tool_offsets).after.mean_um());
    if (k == kStart) start.emplace(std::move(problem));
  }
  const MachineReference reference = IdentifyMachineReference(*start, 1);
  MonteCarloSettings settings;
  settings.runs = 200;
  settings.seed = 1;
  const MachineUncertainty u = RunMachineMonteCarlo(*start, reference, settings, stage::BudgetInputs{});
  const stage::SampleSummary real = stage::SummarizeSample(observed), simulated = stage::SummarizeSample(u.validation_mean_um);
  std::printf("trackergen --seed 3 --truth rich: %d repeats %.2f +- %.2f um; Monte Carlo from repeat %d %.2f +- %.2f um "
              "(ratios: mean %.3f, spread %.3f)\n",
              kRepeats, real.mean, real.sd, kStart, simulated.mean, simulated.sd, simulated.mean / real.mean,
              simulated.sd / real.sd);
  EXPECT_EQ(u.converged, settings.runs);
  EXPECT_GT(simulated.mean / real.mean, 0.8);
  EXPECT_LT(simulated.mean / real.mean, 1.25);
  EXPECT_GT(simulated.sd / real.sd, 0.8);
  EXPECT_LT(simulated.sd / real.sd, 1.25);
}

}  // namespace
}  // namespace fvm::workflows
