// Whole-process figures of the fvm executable (issue 47), each against a baseline timed in the same process, pair
// by pair (subject, baseline, subject, ...), so that a ratio holds when a shared machine's speed drifts:
// - `fvm --version` and `fvm calibrate samples/bar17 --model 27` against /bin/true, the cost of creating any process
//   here (goal: --version within 10 ms, i.e. a few ms above the bare process);
// - `fvm calibrate` on ../shared/bench/fvmgen.py's seed-5 batch, model 27, against the identification alone of
//   ../shared/bench/peer_calibrate.py (scipy's Levenberg-Marquardt, its own timer, order 1 = 27 coefficients;
//   goal >= 50x);
// - `fvm verify` of 5408 readings (trackergen.py --step 100,100,100 --noise), order 3 + pose, against
//   peer_verify.py's fit alone (goal >= 20x).
// The peers are independent code (../shared/bench/README.md); without ../shared or python3 with scipy those two
// benchmarks are skipped. Counters: the subject's and the baseline's median milliseconds, wall and CPU (the
// process's user + system time: what it costs whatever else the machine runs), and their ratios.

#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

const fs::path kShared = fs::path(FVM_SOURCE_DIR) / ".." / "shared" / "bench";

// One finished process: its wall seconds and its CPU seconds (user + system, from the kernel's accounting: on a
// machine shared with other jobs the wall time says how busy the machine was, the CPU time what the process cost).
struct Run {
  double wall = -1.0, cpu = -1.0;
};

// Runs `argv` with stdout and stderr to /dev/null; wall and cpu negative when it failed.
Run RunProcess(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  int status = -1;
  rusage usage{};
  const bool spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ) == 0;
  posix_spawn_file_actions_destroy(&actions);
  if (!spawned || wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return {};
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
          seconds(usage.ru_utime) + seconds(usage.ru_stime)};
}

// What a shell command prints on stdout; empty when it failed.
std::string Output(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[4096];
  for (size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  return pclose(pipe) == 0 ? out : std::string();
}

// The "seconds" a peer's JSON reports (its solve alone, timed by itself); negative when absent.
double PeerSeconds(const std::string& command) {
  const std::string json = Output(command);
  const size_t at = json.find("\"seconds\":");
  return at == std::string::npos ? -1.0 : std::stod(json.substr(at + 10));
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// A scratch directory for the benchmarks' files, removed at exit.
const fs::path& Scratch() {
  struct Directory {
    fs::path path = fs::temp_directory_path() / ("fvm_startup_bench." + std::to_string(getpid()));
    Directory() { fs::create_directories(path); }
    ~Directory() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  };
  static const Directory directory;
  return directory.path;
}

// Subject and baseline in turn; counters: medians in ms (wall and CPU) and their ratios.
void Paired(benchmark::State& state, const std::vector<std::string>& subject, const std::vector<std::string>& baseline) {
  std::vector<double> wall, cpu, base_wall, base_cpu;
  for (auto _ : state) {
    const Run s = RunProcess(subject);
    state.PauseTiming();
    const Run t = RunProcess(baseline);
    state.ResumeTiming();
    if (s.wall < 0 || t.wall < 0) {
      state.SkipWithError(("failed: " + (s.wall < 0 ? subject : baseline).front()).c_str());
      return;
    }
    wall.push_back(s.wall), cpu.push_back(s.cpu), base_wall.push_back(t.wall), base_cpu.push_back(t.cpu);
  }
  state.counters["ms"] = 1e3 * Median(wall);
  state.counters["cpu_ms"] = 1e3 * Median(cpu);
  state.counters["baseline_ms"] = 1e3 * Median(base_wall);
  state.counters["baseline_cpu_ms"] = 1e3 * Median(base_cpu);
  state.counters["ratio"] = Median(wall) / Median(base_wall);
  state.counters["cpu_ratio"] = Median(cpu) / Median(base_cpu);
}

void BM_VersionVsBareProcess(benchmark::State& state) {
  Paired(state, {FVM_EXE, "--version"}, {"/bin/true"});
}
BENCHMARK(BM_VersionVsBareProcess)->Unit(benchmark::kMillisecond)->Iterations(40);

void BM_CalibrateSampleVsBareProcess(benchmark::State& state) {
  Paired(state,
         {FVM_EXE, "calibrate", std::string(FVM_SOURCE_DIR) + "/samples/bar17", "--model", "27", "-o",
          (Scratch() / "bar17.json").string()},
         {"/bin/true"});
}
BENCHMARK(BM_CalibrateSampleVsBareProcess)->Unit(benchmark::kMillisecond)->Iterations(20);

bool PeersAvailable(benchmark::State& state) {
  if (!fs::exists(kShared / "peer_calibrate.py") ||
      Output("/usr/bin/python3 -c 'import numpy, scipy' 2>/dev/null && echo ok") != "ok\n") {
    state.SkipWithError("../shared/bench or python3 with numpy and scipy absent");
    return false;
  }
  return true;
}

// The whole fvm process, each run, against the peer's solve alone (its median over `peer_runs`, its own wall
// clock). Counters: fvm's medians in ms (wall and CPU), the peer's, and how many times faster fvm is (wall against
// wall: both stretch alike when the machine is busy).
void AgainstPeer(benchmark::State& state, const std::vector<std::string>& fvm, const std::string& peer, int peer_runs) {
  std::vector<double> wall, cpu, theirs;
  for (int k = 0; k < peer_runs; ++k) {
    const double s = PeerSeconds(peer);
    if (s <= 0) {
      state.SkipWithError(("the peer failed: " + peer).c_str());
      return;
    }
    theirs.push_back(s);
  }
  for (auto _ : state) {
    const Run r = RunProcess(fvm);
    if (r.wall < 0) {
      state.SkipWithError("fvm failed");
      return;
    }
    wall.push_back(r.wall), cpu.push_back(r.cpu);
  }
  state.counters["ms"] = 1e3 * Median(wall);
  state.counters["cpu_ms"] = 1e3 * Median(cpu);
  state.counters["peer_ms"] = 1e3 * Median(theirs);
  state.counters["times_faster"] = Median(theirs) / Median(wall);
}

void BM_CalibrateVsScipyPeer(benchmark::State& state) {
  if (!PeersAvailable(state)) return;
  const fs::path batch = Scratch() / "fvmgen5";
  if (!fs::exists(batch / "batch.json")) {
    Output("/usr/bin/python3 " + (kShared / "fvmgen.py").string() + " " + batch.string() + " --seed 5 >/dev/null");
  }
  AgainstPeer(state,
              {FVM_EXE, "calibrate", batch.string(), "--model", "27", "-o", (Scratch() / "fvmgen5.json").string()},
              "/usr/bin/python3 " + (kShared / "peer_calibrate.py").string() + " " + batch.string() +
                  " --order 1 --repeat 3",
              3);
}
BENCHMARK(BM_CalibrateVsScipyPeer)->Unit(benchmark::kMillisecond)->Iterations(20);

void BM_Verify5408VsScipyPeer(benchmark::State& state) {
  if (!PeersAvailable(state)) return;
  const fs::path readings = Scratch() / "tracker5408.csv";
  if (!fs::exists(readings)) {
    Output("/usr/bin/python3 " + (kShared / "trackergen.py").string() + " " + readings.string() +
           " --seed 1 --step 100,100,100 --noise >/dev/null");
  }
  AgainstPeer(state,
              {FVM_EXE, "verify", readings.string(), "--chain", "XFYZ", "--order", "3", "--tool", "0,0,100",
               "--fit-pose", "-o", (Scratch() / "machine.json").string()},
              "/usr/bin/python3 " + (kShared / "peer_verify.py").string() + " " + readings.string() +
                  " --order 3 --fit-pose",
              3);
}
BENCHMARK(BM_Verify5408VsScipyPeer)->Unit(benchmark::kMillisecond)->Iterations(10);

// The real confocal grid of ../shared/realdata/tiles/confocal-3x4 (12 colour tiles of 1024 x 1024 px, 17 pairs) and
// its layout as ../shared/bench/check builds it; false where ../shared is absent or the layout cannot be written.
const fs::path kConfocalGrid = kShared / ".." / "realdata" / "tiles" / "confocal-3x4";

bool WriteConfocalLayout(const fs::path& layout) {
  if (!fs::exists(kConfocalGrid / "TileConfiguration.txt")) return false;
  if (fs::exists(layout)) return true;
  std::string text = "file,row,col\n";
  for (int k = 0; k < 12; ++k) {  // serpentine: the middle row runs right to left (its TileConfiguration.txt)
    const int row = k / 4, col = row == 1 ? 3 - k % 4 : k % 4;
    char name[64];
    std::snprintf(name, sizeof name, "x100_epr-jerem_10pct_001_A%03d_I.tif", k + 1);
    text += (fs::canonical(kConfocalGrid) / name).string() + "," + std::to_string(row) + "," + std::to_string(col) + "\n";
  }
  FILE* out = std::fopen(layout.c_str(), "w");
  return out != nullptr && std::fputs(text.c_str(), out) >= 0 && std::fclose(out) == 0;
}

// Issue 42: `fvm stitch --overlap 10` of the confocal grid as a whole process on all cores, against the same
// process with --threads 1 (goal: under 1 s wall on 2 cores). Skipped where ../shared is absent.
void BM_StitchConfocalVsOneThread(benchmark::State& state) {
  const fs::path layout = Scratch() / "confocal_layout.csv";
  if (!WriteConfocalLayout(layout)) {
    state.SkipWithError("../shared/realdata absent");
    return;
  }
  const std::vector<std::string> stitch = {FVM_EXE, "stitch", "--layout", layout.string(), "--overlap", "10", "-o",
                                           (Scratch() / "confocal_positions.csv").string()};
  std::vector<std::string> one_thread = stitch;
  one_thread.insert(one_thread.end(), {"--threads", "1"});
  Paired(state, stitch, one_thread);
}
BENCHMARK(BM_StitchConfocalVsOneThread)->Unit(benchmark::kMillisecond)->Iterations(5);

// Issue 43: `fvm stitch --distortion` on the confocal grid (the rigid registration, dense correspondences in two
// rounds, the joint solve of positions and field, the tiles resampled without it), the whole process on every core
// against the same on one thread (`fvm --threads 1`). Goal: under 5 s wall on 2 cores. Skipped where ../shared is
// absent.
void BM_StitchConfocalDistortionVsOneThread(benchmark::State& state) {
  const fs::path layout = Scratch() / "confocal_layout.csv";
  if (!WriteConfocalLayout(layout)) {
    state.SkipWithError("../shared/realdata absent");
    return;
  }
  const std::vector<std::string> stitch = {"stitch", "--layout", layout.string(), "--overlap", "10", "--distortion",
                                           "-o", (Scratch() / "confocal_distortion_positions.csv").string()};
  std::vector<std::string> subject = {FVM_EXE}, baseline = {FVM_EXE, "--threads", "1"};
  subject.insert(subject.end(), stitch.begin(), stitch.end());
  baseline.insert(baseline.end(), stitch.begin(), stitch.end());
  Paired(state, subject, baseline);
}
BENCHMARK(BM_StitchConfocalDistortionVsOneThread)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
