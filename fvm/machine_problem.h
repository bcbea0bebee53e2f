#pragma once
// The command-line face of the machine-tool jobs (fvm verify, fvm uncertainty, fvm testpiece verify): their shared
// options, which workflows/machine_problem.h turns into an identification problem, and the JSON and report pieces
// their outputs share.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "report/machine_report.h"
#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "workflows/machine_problem.h"

namespace fvm::cli {

struct MachineArgs {
  std::string data;
  std::string chain = "XFYZ";
  std::string basis = "legendre";
  std::vector<std::string> tools{"0,0,0"};
  bool fit_pose = false;
  std::string pose;
  std::string machine;
  std::string tracker = "published";
  bool unweighted = false;
  std::string validate;
  double max_error_mm = 0;  // 0: 1 mm per metre of the longest travel
};

// DATA, --chain, --basis, --tool, --fit-pose, --pose, --machine, --tracker, --unweighted, --validate, --max-error-mm.
void AddMachineOptions(CLI::App* sub, MachineArgs& args);
// --max-error-mm alone (fvm testpiece verify adds its options itself).
void AddMaxErrorOption(CLI::App* sub, MachineArgs& args);

// The options as the job takes them (workflows/machine_problem.h); --threads from the program.
workflows::MachineProblemOptions ProblemOptions(const MachineArgs& args);
// Reads and checks everything (workflows::LoadMachineProblem); bad input is an InputError naming the file, line and
// point.
workflows::MachineProblem LoadMachineProblem(const MachineArgs& args);

using workflows::MachineProblem;
using workflows::NotConvergedReason;

// {"max_error_mm", "largest_term", "largest_share"}: the plausibility bound applied and the identified term that
// comes nearest it (share 1 is the bound).
nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm);

// {"mean_um", "max_um", "min_um"} of a volumetric error.
nlohmann::json ErrorJson(const stage::ResidualSummary& e);
// An instrument pose (tracker, or a test piece's datum): translation, rotation vector, XYZ Euler angles, and the
// standard uncertainties when `covariance` is given.
nlohmann::json PoseJson(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance);

// The report of a verification (fvm verify, fvm testpiece verify): the error functions with their bands, the
// squareness, pose and fixed-term tables, every point's error before and after. `doc` is the command's JSON
// ("chain", "order", "weights", "initial", "final", "validation", "pose" with "estimated").
report::MachineReportData MachineVerificationReport(const MachineArgs& args, const nlohmann::json& doc, const stage::VerificationResult& v,
                                            const std::vector<stage::Observation>& observations,
                                            const std::vector<stage::Observation>* validation,
                                            const std::vector<Eigen::Vector3d>& tools);

}  // namespace fvm::cli
