#pragma once
// Progress of long work on a terminal: "label: done/total" redrawn in place (\r), at most every 100 ms, and one
// final line when the work ends. Silent when disabled (not a terminal, or --quiet), so logs and pipes get no
// carriage returns. Advance() may be called from several threads at once (pairs register on a thread pool).

#include <chrono>
#include <iosfwd>
#include <mutex>
#include <string>

namespace fvm {

// Wall-clock seconds since `start`: how long a job took, for its summary.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// True when stderr is a terminal: the only place a redrawn line makes sense.
bool StderrIsTerminal();

class Progress {
 public:
  // Draws on stderr.
  Progress(std::string label, int total, bool enabled);
  // Draws on `out` (tests).
  Progress(std::string label, int total, bool enabled, std::ostream& out);
  ~Progress();  // ends the line if Finish() was not called (an exception unwound the work)
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Advance(int steps = 1);
  // Draws the final "label: done/total" line; later calls do nothing.
  void Finish();
  int done() const;

 private:
  void Draw(bool final_line);  // caller holds mutex_

  std::string label_;
  int total_;
  bool enabled_;
  std::ostream& out_;
  mutable std::mutex mutex_;
  int done_ = 0;
  bool drawn_ = false;
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace fvm
