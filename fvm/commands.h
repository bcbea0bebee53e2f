#pragma once
// Every subcommand registers itself on the application from its own file (fvm/<command>.cc).

#include <CLI/CLI.hpp>

namespace fvm::cli {

// A subcommand that is listed in the contract but not built yet: it says so and exits 2.
void AddNotBuilt(CLI::App& app, const std::string& name, const std::string& summary, int issue);

}  // namespace fvm::cli
