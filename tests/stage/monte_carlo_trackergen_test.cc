// The machine Monte Carlo against repeats of machines the project did not make: ../shared/bench's trackergen.py
// (written apart from this code; --truth rich: cubics plus ball-screw and waviness sines no polynomial follows,
// squareness per machine; the published tracker noise) reads machines 4, 5 and 6 again and again with fresh noise
// (--noise-seed), as `bash ../shared/bench/check uncertainty` does for machine 4. Each repeat is verified as
// fvm verify --chain XFYZ --order 1 --tool 0,0,100 --fit-pose --validate does, on the machine's noise-free
// validation mesh, and the Monte Carlo from one repeat alone must predict the mean and the spread (sd) of the
// repeats' validation mean errors, whichever repeat it starts from. Skips where ../shared or Debian's python3-numpy
// and python3-scipy are absent.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "artefacts/io/tracker_readings.h"
#include "artefacts/tracker_observations.h"
#include "stage/machine_verification.h"
#include "stage/monte_carlo.h"
#include "tests/support/test_support.h"

namespace fvm::stage {
namespace {

const std::filesystem::path kTrackergen = std::filesystem::path(FVM_BENCH_DIR) / "trackergen.py";

bool TrackergenAvailable() {
  return std::filesystem::exists(kTrackergen) && std::system("/usr/bin/python3 -c 'import numpy, scipy' >/dev/null 2>&1") == 0;
}

// trackergen.py's own main in one Python process (nothing written beside the bench): for each machine seed S,
// DIR/S/val.csv (noise-free, --step 250,250,200) and DIR/S/dK.csv (--noise --noise-seed K) for K in 1..repeats.
void Generate(const std::filesystem::path& dir, const std::vector<int>& seeds, int repeats) {
  const std::string script =
      "import sys, io, os, contextlib\n"
      "sys.dont_write_bytecode = True\n"
      "sys.path.insert(0, sys.argv[1]); import trackergen\n"
      "d, n = sys.argv[2], int(sys.argv[3])\n"
      "for seed in sys.argv[4:]:\n"
      "    os.makedirs(d + '/' + seed)\n"
      "    for name, extra in [('val.csv', ['--step', '250,250,200'])]"
      " + [('d%d.csv' % k, ['--noise', '--noise-seed', str(k)]) for k in range(1, n + 1)]:\n"
      "        sys.argv = ['trackergen.py', d + '/' + seed + '/' + name, '--seed', seed, '--truth', 'rich'] + extra\n"
      "        with contextlib.redirect_stdout(io.StringIO()): trackergen.main()\n";
  std::string command = "/usr/bin/python3 -c \"" + script + "\" '" + kTrackergen.parent_path().string() + "' '" +
                        dir.string() + "' " + std::to_string(repeats);
  for (int s : seeds) command += " " + std::to_string(s);
  command += " >/dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
}

// What fvm verify builds from the files: XFYZ, Legendre of order 1 on the span of the commanded points, tool
// 0,0,100 mm, the pose estimated, each reading weighted by the published tracker noise.
ParameterLayout SpanLayout(const std::filesystem::path& readings, const Eigen::Vector3d& tool) {
  const artefacts::TrackerReadings read = artefacts::ReadTrackerReadings(readings);
  std::array<Travel, 3> travel;
  for (int k = 0; k < 3; ++k) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const artefacts::TrackerReading& r : read.points) lo = std::min(lo, r.nominal[k]), hi = std::max(hi, r.nominal[k]);
    travel[static_cast<size_t>(k)] = Travel{lo, hi};
  }
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.tool_offset = tool;
  return MachineLayout(chain, travel, Basis::kLegendre, 1);
}

struct Machine {
  TrackerNoise noise = TrackerNoise::Preset("published");
  std::vector<Eigen::Vector3d> tools{Eigen::Vector3d(0, 0, 100)};
  std::vector<Observation> validation;  // with the tracker's covariances (the Monte Carlo tells they are noise-free)
  ParameterLayout layout;
  IdentificationOptions options;

  explicit Machine(const std::filesystem::path& dir)
      : validation(artefacts::TrackerObservations(artefacts::ReadTrackerReadings(dir / "val.csv"), &noise)),
        layout(SpanLayout(dir / "d1.csv", tools.front())) {
    options.tool_offsets = tools;
    options.instrument = InstrumentPose::kEstimated;
    options.num_threads = 1;
  }
  std::vector<Observation> Readings(const std::filesystem::path& file) const {
    return artefacts::TrackerObservations(artefacts::ReadTrackerReadings(file), &noise);
  }
  double ValidationMeanUm(const VerificationResult& v) const {
    const Calibration& c = v.identified.calibration;
    return Summarize(VolumetricResiduals(c.layout, &c.values, v.identified.pose, validation, tools)).mean_um();
  }

  // Every repeat d1..dN of `dir` verified: its validation mean error; the first `starts` kept as Monte Carlo starts.
  struct Repeats {
    std::vector<double> observed;
    std::vector<std::vector<Observation>> readings;
    std::vector<VerificationResult> verified;
  };
  Repeats VerifyRepeats(const std::filesystem::path& dir, int repeats, int starts) const {
    Repeats out;
    for (int k = 1; k <= repeats; ++k) {
      std::string name = "d";
      name += std::to_string(k) + ".csv";
      std::vector<Observation> readings = Readings(dir / name);
      VerificationResult v = VerifyMachine(layout, readings, options);
      out.observed.push_back(ValidationMeanUm(v));
      if (k <= starts) out.readings.push_back(std::move(readings)), out.verified.push_back(std::move(v));
    }
    return out;
  }

  // The validation mean error of each of `runs` Monte Carlo runs from repeat `start` (0-based).
  std::vector<double> PredictedMeans(const Repeats& r, int start, int runs) const {
    MonteCarloOptions mc;
    mc.runs = runs;
    mc.seed = 1;
    std::vector<double> predicted;
    for (const MachineMonteCarloRun& run : MachineMonteCarlo(layout, r.verified[static_cast<size_t>(start)],
                                                             r.readings[static_cast<size_t>(start)], validation, noise,
                                                             options, mc)) {
      predicted.push_back(run.validation.mean_um());
    }
    return predicted;
  }
};

// Three machines, 150 repeats each (the sd of their validation mean error, a skewed quantity, known to about 8 %),
// the Monte Carlo (150 runs) from two repeats of each: the first (what check does) and the one of repeats 1-12
// whose own validation error is largest, the hardest start, whose model is furthest from the machine. With the
// field's power judged direction by direction, the reference's own estimation error stayed in the validation truth
// and the prediction followed the start: from the hardest starts the spread came out 1.19, 1.28 and 1.16 of the
// repeats' (1.36, 1.20, 1.27 against 200 repeats; stage/residual_field.h), 1.06, 1.03 and 0.88 now. Bounds: the
// issue's 0.8-1.25 for both ratios. About 20 s on 2 cores. (A dozen repeats cannot judge this: the sd of 12 draws
// of a quantity this skewed is below 1 / 1.4 of the truth's one time in seven, and trackergen's noise seeds 1-12,
// the same noise for every machine, give 0.44-0.79 of what 200 repeats give on machines 4-6.)
TEST(MachineMonteCarloTrackergen, PredictsRepeatsOfThreeMachinesFromAnyStart) {
  if (!TrackergenAvailable()) GTEST_SKIP() << kTrackergen << " or python3-numpy/scipy absent (no ../shared)";
  constexpr int kRepeats = 150, kCandidates = 12;
  const std::vector<int> seeds{4, 5, 6};
  fvm::testing::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(Generate(dir.path(), seeds, kRepeats));
  for (int seed : seeds) {
    const std::filesystem::path at = dir.path() / std::to_string(seed);
    const Machine machine(at);
    const Machine::Repeats repeats = machine.VerifyRepeats(at, kRepeats, kCandidates);
    const std::vector<double>& observed = repeats.observed;
    const SampleSummary real = SummarizeSample(observed);
    const int hardest = static_cast<int>(std::max_element(observed.begin(), observed.begin() + kCandidates) - observed.begin());
    for (int start : {0, hardest}) {
      const SampleSummary simulated = SummarizeSample(machine.PredictedMeans(repeats, start, 150));
      std::printf("trackergen --seed %d --truth rich: %d repeats %.2f +- %.2f um; Monte Carlo from repeat %d (its own "
                  "%.2f um) %.2f +- %.2f um (ratios: mean %.3f, spread %.3f)\n",
                  seed, kRepeats, real.mean, real.sd, start + 1, observed[static_cast<size_t>(start)], simulated.mean,
                  simulated.sd, simulated.mean / real.mean, simulated.sd / real.sd);
      EXPECT_GT(simulated.mean / real.mean, 0.8) << "machine " << seed << ", from repeat " << start + 1;
      EXPECT_LT(simulated.mean / real.mean, 1.25) << "machine " << seed << ", from repeat " << start + 1;
      EXPECT_GT(simulated.sd / real.sd, 0.8) << "machine " << seed << ", from repeat " << start + 1;
      EXPECT_LT(simulated.sd / real.sd, 1.25) << "machine " << seed << ", from repeat " << start + 1;
    }
  }
}

// The robust spread of n draws: 1.4826 x the median absolute deviation and the interquartile range / 1.349 (both the
// sd for a normal sample, both blind to the few far repeats a skewed quantity has), and the 2.5 / 97.5 % quantiles.
struct TrackergenCore {
  double mean = 0, mad = 0, iqr = 0, p2_5 = 0, p97_5 = 0;
};
double TrackergenQuantile(const std::vector<double>& sorted, double p) {
  const double at = p * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(at), hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (at - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}
TrackergenCore CoreOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  TrackergenCore c;
  for (double x : v) c.mean += x / static_cast<double>(v.size());
  const double median = TrackergenQuantile(v, 0.5);
  std::vector<double> deviations;
  for (double x : v) deviations.push_back(std::abs(x - median));
  std::sort(deviations.begin(), deviations.end());
  c.mad = 1.4826 * TrackergenQuantile(deviations, 0.5);
  c.iqr = (TrackergenQuantile(v, 0.75) - TrackergenQuantile(v, 0.25)) / 1.349;
  c.p2_5 = TrackergenQuantile(v, 0.025);
  c.p97_5 = TrackergenQuantile(v, 0.975);
  return c;
}

// The core of the distribution, not only its sd, on a fourth machine (3): the sd of a skewed quantity leans on its
// few far repeats (noise seed 41 gives 22 um on every machine, 5 sd above the mean: an estimation error along the
// X axis' yaw, its scale and the tracker's x at once, the 3rd largest chi^2 of the 17 estimates over 400 repeats;
// the validation mean error is a quadratic form of the estimates, hence the skew 0.9-1.2), so the Monte Carlo is
// judged here by the robust spreads, which those repeats do not move, and by how many repeats its 95 % interval
// holds. 160 repeats; the Monte Carlo (300 runs) from the first repeat and from the calmest and the hardest of
// repeats 1-12. Against 400 repeats of each of machines 3-8 (tests/bench/uncertainty_repeats.sh) the ratios are
// 0.97-1.02 (mean), 0.91-1.17 (MAD) and 0.94-1.19 (IQR), each machine's average over its starts; a Monte Carlo with
// the machine's exact truth (started from noise-free readings, its exact residual field: the repeats' own process)
// gives the same (0.92-1.15 for MAD and IQR): what is left is the repeats' own sampling. Bounds: the 0.8-1.25;
// the 95 % interval must hold at least 87 % of the repeats: the binomial sd of 95 % on 160 repeats is 1.7 % and the
// quantiles of 300 runs add about 1 % (2.5 sd: 90 %), and from the calmest start the interval sits low (mean 0.94 of
// the repeats': a start whose model happens to be nearer the machine than most cannot tell the machine's unfollowed
// part any better) and holds 89 %. It fails with the validation truth keeping the start's whole residual (its
// estimation error with it, as two rounds ago: MAD 1.22 and 1.59 from repeats 1 and 8, intervals holding 53-66 %)
// and with no unfollowed part in the truth (mean 0.56-0.58, MAD 1.48). About 10 s on 2 cores.
TEST(MachineMonteCarloTrackergen, MatchesTheCoreOfRepeatsOfAFourthMachine) {
  if (!TrackergenAvailable()) GTEST_SKIP() << kTrackergen << " or python3-numpy/scipy absent (no ../shared)";
  constexpr int kRepeats = 160, kCandidates = 12, kSeed = 3;
  fvm::testing::TempDir dir;
  ASSERT_NO_FATAL_FAILURE(Generate(dir.path(), {kSeed}, kRepeats));
  const std::filesystem::path at = dir.path() / std::to_string(kSeed);
  const Machine machine(at);
  const Machine::Repeats repeats = machine.VerifyRepeats(at, kRepeats, kCandidates);
  const std::vector<double>& observed = repeats.observed;
  const TrackergenCore real = CoreOf(observed);
  const auto first12 = observed.begin() + kCandidates;
  const int calmest = static_cast<int>(std::min_element(observed.begin(), first12) - observed.begin());
  const int hardest = static_cast<int>(std::max_element(observed.begin(), first12) - observed.begin());
  for (int start : {0, calmest, hardest}) {
    const TrackergenCore simulated = CoreOf(machine.PredictedMeans(repeats, start, 300));
    const double held = static_cast<double>(std::count_if(observed.begin(), observed.end(), [&](double v) {
                          return v >= simulated.p2_5 && v <= simulated.p97_5;
                        })) / kRepeats;
    std::printf("trackergen --seed %d: %d repeats mean %.2f, MAD %.2f, IQR %.2f um; Monte Carlo from repeat %d (its own "
                "%.2f um): ratios mean %.3f, MAD %.3f, IQR %.3f; its 95 %% interval %.2f-%.2f um holds %.1f %% of the "
                "repeats\n",
                kSeed, kRepeats, real.mean, real.mad, real.iqr, start + 1, observed[static_cast<size_t>(start)],
                simulated.mean / real.mean, simulated.mad / real.mad, simulated.iqr / real.iqr, simulated.p2_5,
                simulated.p97_5, 100 * held);
    const std::string where = "from repeat " + std::to_string(start + 1);
    EXPECT_GT(simulated.mean / real.mean, 0.8) << where;
    EXPECT_LT(simulated.mean / real.mean, 1.25) << where;
    EXPECT_GT(simulated.mad / real.mad, 0.8) << where;
    EXPECT_LT(simulated.mad / real.mad, 1.25) << where;
    EXPECT_GT(simulated.iqr / real.iqr, 0.8) << where;
    EXPECT_LT(simulated.iqr / real.iqr, 1.25) << where;
    EXPECT_GE(held, 0.87) << where;
  }
}

}  // namespace
}  // namespace fvm::stage
