#pragma once
// An error in what the user gave us: it names the file (and line, calotte id) and says what to do. It lives in
// core/, below every module, so that stage (calibration files, parameter names) can raise it as imaging does.

#include <stdexcept>
#include <string>

namespace fvm {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace fvm
