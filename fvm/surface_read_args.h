#pragma once
// The command-line options that say how to read a surface or cloud file (fvm info, fvm fit, ...), bound to
// workflows::SurfaceReadOptions.

#include <CLI/CLI.hpp>

#include "workflows/surface_read_options.h"

namespace fvm::cli {

void AddSurfaceReadOptions(CLI::App& app, workflows::SurfaceReadOptions& read);

// The same options with their binding, for a command that keeps them beside its own (fvm correct).
struct SurfaceReadArgs : workflows::SurfaceReadOptions {
  void AddOptions(CLI::App& app) { AddSurfaceReadOptions(app, *this); }
};

}  // namespace fvm::cli
