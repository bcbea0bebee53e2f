#pragma once
// The options every machine-tool command shares (fvm verify, fvm uncertainty, fvm testpiece verify), bound straight
// into the job's workflows::MachineProblemOptions: the texts (--tool 0,0,100, --pose, --machine) parsed as CLI11
// reads them, after their checks.

#include <CLI/CLI.hpp>

#include "workflows/machine_problem.h"

namespace fvm::cli {

// DATA, --chain, --basis, --tool, --fit-pose, --pose, --machine, --tracker, --unweighted, --validate, --max-error-mm.
void AddMachineOptions(CLI::App* sub, workflows::MachineProblemOptions& o);
// --tool alone, its default shown as `o.tools` holds it.
void AddToolOption(CLI::App* sub, workflows::MachineProblemOptions& o, const std::string& description);
// --machine alone.
void AddTravelOption(CLI::App* sub, workflows::MachineProblemOptions& o, const std::string& description);
// --max-error-mm alone (fvm testpiece verify adds its options itself).
void AddMaxErrorOption(CLI::App* sub, workflows::MachineProblemOptions& o);

}  // namespace fvm::cli
