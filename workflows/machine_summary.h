#pragma once
// The pieces every machine-tool summary shares (fvm verify, fvm testpiece verify, fvm uncertainty): the JSON of a
// volumetric error, of an instrument pose and of the plausibility bound, and the report page of a verification.

#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "report/machine_report.h"
#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "workflows/machine_problem.h"

namespace fvm::workflows {

// A pose's rotation as intrinsic XYZ Euler angles (deg).
Eigen::Vector3d EulerXyzDeg(const stage::Pose& pose);
// {"mean_um", "max_um", "min_um"} of a volumetric error.
nlohmann::json ErrorJson(const stage::ResidualSummary& e);
// An instrument pose (tracker, or a test piece's datum): translation, rotation vector, XYZ Euler angles, and the
// standard uncertainties when `covariance` is given.
nlohmann::json PoseJson(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance);
// {"max_error_mm", "largest_term", "largest_share"}: the plausibility bound applied and the identified term that
// comes nearest it (share 1 is the bound).
nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm);
// The JSON both verifications share: chain, basis, order, points, initial and final errors, validation, pose (held
// or estimated, with its initial value), fixed and parameters, plausibility, converged (and the solver's report
// when not).
nlohmann::json VerificationJson(const MachineProblem& problem, const MachineProblemOptions& options, int order,
                                const stage::VerificationResult& v, const std::optional<VolumetricChange>& validation);

// The report of a verification (fvm verify, fvm testpiece verify): the error functions sampled over each axis' travel
// with their bands, the squareness, pose and fixed-term tables, every point's error before and after. `title` heads
// the page; `weights` names the readings' weights in its summary.
report::MachineReportData VerificationReport(const std::string& title, const std::string& weights,
                                             const MachineProblem& problem, const stage::VerificationResult& v,
                                             const std::optional<VolumetricChange>& validation);

}  // namespace fvm::workflows
