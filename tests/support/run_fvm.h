#pragma once
// Running the fvm executable as a user does, from a GoogleTest: its exit status, stdout and stderr. The test
// target defines FVM_EXE (the executable's path) and depends on the fvm target.

#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "tests/support/test_support.h"

namespace fvm::testing {

struct FvmRun {
  int status = 0;
  std::string out, err;
};

inline FvmRun RunFvm(const TempDir& dir, const std::string& arguments) {
  const std::string err_file = (dir / "stderr.txt").string();
  const std::string command = std::string(FVM_EXE) + " " + arguments + " 2>" + err_file;
  FvmRun run;
  FILE* pipe = popen(command.c_str(), "r");
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) run.out.append(buffer, n);
  const int status = pclose(pipe);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.err = ReadText(err_file);
  return run;
}

}  // namespace fvm::testing
