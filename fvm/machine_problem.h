#pragma once
// What fvm verify and fvm uncertainty share: the tracker readings and their options turned into an identification
// problem (chain, tool offsets, weights, workspace, pose held or estimated), with the same checks and messages.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "artefacts/io/tracker_readings.h"
#include "core/input_error.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "fvm/machine_report.h"
#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "stage/tracker.h"

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

struct MachineProblem {
  artefacts::TrackerReadings readings;
  std::optional<artefacts::TrackerReadings> validation;
  stage::AxisChain chain;              // tool offset: the first --tool
  stage::IdentificationOptions options;  // tool offsets, instrument held or estimated, pose, threads
  stage::TrackerNoise noise;
  bool weighted = true;
  std::vector<stage::Observation> observations;  // the readings, weighted by the noise model when `weighted`
  std::vector<stage::Observation> validation_observations;  // unweighted; empty without --validate
  artefacts::Workspace workspace;      // --machine, or the span of the commanded points
  stage::Basis basis = stage::Basis::kLegendre;
  std::string WeightsName() const;     // "tracker published" or "equal"
  stage::ParameterLayout Layout(int order) const;
};

// Reads and checks everything; bad input is an InputError naming the file, line and point.
MachineProblem LoadMachineProblem(const MachineArgs& args);

// Identifies `layout` (VerifyMachine); a refusal is an InputError naming the data file (an implausible result says
// how to raise the bound). Then refuses readings the tracker could not have made from the pose found.
stage::VerificationResult VerifyProblem(const MachineProblem& problem, const stage::ParameterLayout& layout);
// The InputError for a verification's refusal: the data file and the reason; for an implausible result
// (stage::ImplausibleFit) also how to raise the bound.
InputError VerificationRefusal(const std::string& source, const std::invalid_argument& refusal);
void CheckTrackerSight(const MachineProblem& problem, const stage::Pose& pose);

// The one-line reason an identification did not converge, for exit 3 ("the identification stopped at its limit of
// 100 iterations before the fit settled: ..."): what happened and what to try, without the solver's raw report
// (which --json carries as "solver_report").
std::string NotConvergedReason(const stage::IdentificationResult& identified);

// {"max_error_mm", "largest_term", "largest_share"}: the plausibility bound applied and the identified term that
// comes nearest it (share 1 is the bound).
nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm);

// {"mean_um", "max_um", "min_um"} of a volumetric error.
nlohmann::json ErrorJson(const stage::VolumetricError& e);
// An instrument pose (tracker, or a test piece's datum): translation, rotation vector, XYZ Euler angles, and the
// standard uncertainties when `covariance` is given.
nlohmann::json PoseJson(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance);

// The report of a verification (fvm verify, fvm testpiece verify): the error functions with their bands, the
// squareness, pose and fixed-term tables, every point's error before and after. `doc` is the command's JSON
// ("chain", "order", "weights", "initial", "final", "validation", "pose" with "estimated").
MachineReportData MachineVerificationReport(const MachineArgs& args, const nlohmann::json& doc, const stage::VerificationResult& v,
                                            const std::vector<stage::Observation>& observations,
                                            const std::vector<stage::Observation>* validation,
                                            const std::vector<Eigen::Vector3d>& tools);

}  // namespace fvm::cli
