#pragma once
// The command-line face of the model choice and identification settings that calibrate, compare, diagnose and
// uncertainty share (workflows/model_choice.h).

#include <CLI/CLI.hpp>

#include "workflows/model_choice.h"

namespace fvm::cli {

// --anchor, --stitched-frame, --loss, --loss-scale-um.
void AddIdentifyOptions(CLI::App& app, workflows::IdentifySettings& settings);

// The settings with the program's --threads.
workflows::IdentifySettings Threaded(workflows::IdentifySettings settings);

using workflows::JoinNames;

}  // namespace fvm::cli
