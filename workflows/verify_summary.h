#pragma once
// What fvm verify tells its user (workflows/summary.h): the --json document, the printed lines and the report page
// of a machine verification, and the machine file -o writes.

#include <nlohmann/json.hpp>

#include <string>

#include "workflows/summary.h"
#include "workflows/verify_machine.h"

namespace fvm::workflows {

// `model_file`: where the front end writes MachineModelJson (the text says so); empty when it writes none.
Summary Summarize(const MachineProblem& problem, const VerifyMachineOptions& options,
                  const MachineVerification& verified, const std::string& model_file = "");

// The identified machine (-o): the calibration JSON with the model's name, the tracker pose and the verification's
// errors; the front end adds the readings' path as verification.data.
nlohmann::json MachineModelJson(const MachineProblem& problem, const VerifyMachineOptions& options,
                                const MachineVerification& verified);

}  // namespace fvm::workflows
