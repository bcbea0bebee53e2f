#include <algorithm>
#include <thread>

#include "core/progress.h"
#include "fvm/commands.h"

namespace fvm::cli {

CommonOptions& Common() {
  static CommonOptions options;
  return options;
}

bool ShowProgress() { return !Common().quiet && StderrIsTerminal(); }

int ThreadCount() {
  if (Common().threads > 0) return Common().threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace fvm::cli
