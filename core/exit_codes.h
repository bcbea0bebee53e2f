#pragma once
// The exit codes of `fvm`, a contract for scripts (printed in `fvm --help`), and the error that maps to "did not
// converge". Lives in core/ so that stage and imaging can raise NotConvergedError without knowing the CLI.

#include <stdexcept>
#include <string>

namespace fvm {

enum ExitCode : int {
  kExitOk = 0,
  kExitBadInput = 1,     // fvm::InputError (and any other failure): a file, value or combination to fix
  kExitUsage = 2,        // the command line itself: unknown option, missing argument, command not built yet
  kExitNotConverged = 3, // the work ran but its solver did not converge; outputs written are marked so
};

// A solver that ran out of iterations or stalled: the result exists but must not be trusted as is.
struct NotConvergedError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace fvm
