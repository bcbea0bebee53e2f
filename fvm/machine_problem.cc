#include "fvm/machine_problem.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <cmath>

#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "stage/error_terms.h"
#include "stage/plausibility.h"

namespace fvm::cli {

void AddMachineOptions(CLI::App* sub, MachineArgs& args) {
  sub->add_option("DATA", args.data, "tracker readings: id,x,y,z + xt,yt,zt or range,azimuth,elevation (mm, rad); fvm uncertainty also takes a batch directory")
      ->required();
  sub->add_option("--chain", args.chain, "F-notation chain: letters left of F move the part (e.g. XFYZ, FXYZ, XYFZ)")
      ->capture_default_str();
  sub->add_option("--basis", args.basis, "polynomial basis")->check(CLI::IsMember({"power", "legendre", "chebyshev"}))
      ->capture_default_str();
  sub->add_option("--tool", args.tools, "tool offset X,Y,Z in mm (give it twice for two tools: a `tool` column says which)")
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->capture_default_str();
  auto* fit = sub->add_flag("--fit-pose", args.fit_pose, "estimate the tracker pose jointly (the default)");
  sub->add_option("--pose", args.pose, "hold the tracker pose: X,Y,Z (mm), A,B,C (XYZ Euler, deg)")
      ->check(PoseCheck("--pose"))
      ->excludes(fit);
  sub->add_option("--machine", args.machine, "axis travels LXxLYxLZ[@X0,Y0,Z0] in mm (default: the span of the points)")
      ->check(MachineCheck());
  sub->add_option("--tracker", args.tracker, "tracker noise model for the weights")
      ->check(CLI::IsMember(stage::TrackerNoise::PresetNames()))
      ->capture_default_str();
  sub->add_flag("--unweighted", args.unweighted, "equal weights instead of the readings' covariances (their cxx..czz columns, or the tracker's noise model)");
  sub->add_option("--validate", args.validate, "other readings to judge the model on (never fitted)");
  AddMaxErrorOption(sub, args);
}

void AddMaxErrorOption(CLI::App* sub, MachineArgs& args) {
  sub->add_option("--max-error-mm", args.max_error_mm,
                  "plausibility bound: refuse a result with an error term or residual beyond it, which means wrong data "
                  "(mirrored axes, units, columns), not a machine (default: 1 mm per metre of the longest travel; "
                  "e.g. --max-error-mm 5)")
      ->check(Within(1e-3, 1e5, "mm"));
}

workflows::MachineProblemOptions ProblemOptions(const MachineArgs& args) {
  workflows::MachineProblemOptions o;
  o.data = args.data;
  o.validate = args.validate;
  o.chain = args.chain;
  o.basis = args.basis;
  o.tools.clear();
  for (const std::string& t : args.tools) o.tools.push_back(ParseVector3(t, "--tool", "0,0,100"));
  if (!args.pose.empty()) o.pose = ParsePose(args.pose, "--pose");
  if (!args.machine.empty()) {
    o.travel = ParseMachine(args.machine);
    o.travel_name = fmt::format("--machine '{}'", args.machine);
  }
  o.tracker = args.tracker;
  o.unweighted = args.unweighted;
  o.max_error_mm = args.max_error_mm;
  o.threads = ThreadCount();
  return o;
}

workflows::MachineProblem LoadMachineProblem(const MachineArgs& args) {
  return workflows::LoadMachineProblem(ProblemOptions(args));
}

nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm) {
  const double bound = max_error_mm > 0 ? max_error_mm : stage::DefaultMaxErrorMm(identified.calibration.layout);
  const stage::TermExcess largest = stage::LargestExcess(identified.calibration, bound);
  return {{"max_error_mm", bound},
          {"largest_term", largest.term >= 0 ? std::string(stage::GetErrorTerm(largest.term).vdi) : std::string()},
          {"largest_share", largest.share}};
}

nlohmann::json ErrorJson(const stage::ResidualSummary& e) {
  return {{"mean_um", e.mean_um()}, {"max_um", e.max_um()}, {"min_um", e.min_um()}};
}

nlohmann::json PoseJson(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance) {
  const Eigen::Vector3d euler = pose.Rotation().eulerAngles(0, 1, 2) * 180.0 / M_PI;
  nlohmann::json j{{"translation_mm", {pose.translation.x(), pose.translation.y(), pose.translation.z()}},
                   {"rotation_vector_rad", {pose.rotation.x(), pose.rotation.y(), pose.rotation.z()}},
                   {"euler_xyz_deg", {euler.x(), euler.y(), euler.z()}}};
  if (covariance != nullptr) {
    const Eigen::Matrix<double, 6, 1> u = covariance->diagonal().cwiseMax(0.0).cwiseSqrt();
    j["u_translation_um"] = {u[0] * 1e3, u[1] * 1e3, u[2] * 1e3};
    j["u_rotation_urad"] = {u[3] * 1e6, u[4] * 1e6, u[5] * 1e6};
  }
  return j;
}

}  // namespace fvm::cli
