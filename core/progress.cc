#include "core/progress.h"

#include <unistd.h>

#include <iostream>
#include <utility>

namespace fvm {
namespace {
// Often enough to look alive, rarely enough that 10^5 tiny steps do not spend their time drawing.
constexpr std::chrono::milliseconds kRedrawEvery{100};
}  // namespace

bool StderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(std::string label, int total, bool enabled) : Progress(std::move(label), total, enabled, std::cerr) {}

Progress::Progress(std::string label, int total, bool enabled, std::ostream& out)
    : label_(std::move(label)), total_(total), enabled_(enabled), out_(out) {}

Progress::~Progress() {
  std::lock_guard<std::mutex> lock(mutex_);
  // Unwinding: leave the last count on screen and the cursor on a fresh line for the error message.
  if (enabled_ && drawn_ && !finished_) out_ << '\n' << std::flush;
}

void Progress::Advance(int steps) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ += steps;
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < kRedrawEvery) return;
  last_draw_ = now;
  Draw(false);
}

void Progress::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (enabled_) Draw(true);
}

int Progress::done() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return done_;
}

void Progress::Draw(bool final_line) {
  out_ << '\r' << label_ << ": " << done_ << '/' << total_;
  if (final_line) out_ << '\n';
  out_ << std::flush;
  drawn_ = true;
}

}  // namespace fvm
