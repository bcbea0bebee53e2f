#pragma once
// An error in what the user gave us: it names the file (and line, calotte id) and says what to do. It lives in
// imaging/ because imaging is the lowest layer that reads user files; artefacts and fvm reach it from there.

#include <stdexcept>
#include <string>

namespace fvm {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace fvm
