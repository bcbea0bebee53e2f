#include "fvm/machine_problem.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "artefacts/tracker_observations.h"
#include "core/input_error.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "stage/error_terms.h"
#include "stage/plausibility.h"

namespace fvm::cli {
namespace {

// --machine must hold every commanded point: the polynomial bases are defined on the travel only (Legendre and
// Chebyshev on [-1, 1]); far outside it their powers mean nothing, and overflow.
void CheckInsideTravel(const MachineArgs& args, const artefacts::Workspace& ws, const artefacts::TrackerReadings& readings) {
  constexpr double kToleranceMm = 1e-3;
  for (const artefacts::TrackerReading& r : readings.points) {
    for (int k = 0; k < 3; ++k) {
      if (r.nominal[k] < ws.min[k] - kToleranceMm || r.nominal[k] > ws.max[k] + kToleranceMm) {
        throw InputError(fmt::format(
            "--machine '{}': {}:{}: point {} has {} = {} mm, outside the declared {} travel {} .. {} mm; give travels "
            "that hold every point (LXxLYxLZ@X0,Y0,Z0), or leave --machine out to take the span of the points",
            args.machine, readings.source, r.line, r.id, "xyz"[k], ReadableNumber(r.nominal[k]), "XYZ"[k],
            ReadableNumber(ws.min[k]), ReadableNumber(ws.max[k])));
      }
    }
  }
}

// The workspace the error functions are defined on: --machine, or the span of the commanded points.
artefacts::Workspace WorkspaceOf(const MachineArgs& args, const artefacts::TrackerReadings& readings,
                                 const std::optional<artefacts::TrackerReadings>& validation) {
  if (!args.machine.empty()) {
    const artefacts::Workspace ws = ParseMachine(args.machine);
    CheckInsideTravel(args, ws, readings);
    if (validation) CheckInsideTravel(args, ws, *validation);
    return ws;
  }
  artefacts::Workspace ws;
  ws.min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  ws.max = -ws.min;
  for (const artefacts::TrackerReading& r : readings.points) {
    ws.min = ws.min.cwiseMin(r.nominal);
    ws.max = ws.max.cwiseMax(r.nominal);
  }
  for (int k = 0; k < 3; ++k) {
    if (!(ws.max[k] > ws.min[k])) {
      throw InputError(fmt::format("{}: every point has {} = {} mm: the {} axis never moves, so its errors cannot be "
                                   "identified; measure points along all three axes",
                                   readings.source, "xyz"[k], ws.min[k], "XYZ"[k]));
    }
  }
  return ws;
}

}  // namespace

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
  sub->add_flag("--unweighted", args.unweighted, "equal weights instead of the tracker's covariances");
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

std::string MachineProblem::WeightsName() const { return weighted ? "tracker " + noise.name : std::string("equal"); }

stage::ParameterLayout MachineProblem::Layout(int order) const {
  std::array<stage::Travel, 3> travel;
  for (int k = 0; k < 3; ++k) travel[static_cast<size_t>(k)] = stage::Travel{workspace.min[k], workspace.max[k]};
  return stage::MachineLayout(chain, travel, basis, order);
}

MachineProblem LoadMachineProblem(const MachineArgs& args) {
  MachineProblem p;
  p.readings = artefacts::ReadTrackerReadings(args.data);
  if (!args.validate.empty()) p.validation = artefacts::ReadTrackerReadings(args.validate);
  try {
    p.chain = stage::AxisChain::Parse(args.chain);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("--chain {}: {}", args.chain, e.what()));
  }
  for (const std::string& t : args.tools) p.options.tool_offsets.push_back(ParseVector3(t, "--tool", "0,0,100"));
  p.chain.tool_offset = p.options.tool_offsets.front();
  for (const artefacts::TrackerReadings* file : {&p.readings, p.validation ? &*p.validation : nullptr}) {
    if (file == nullptr) continue;
    for (const artefacts::TrackerReading& r : file->points) {
      if (r.tool >= static_cast<int>(p.options.tool_offsets.size())) {
        throw InputError(fmt::format("{}:{}: point {} was measured with tool {}, but only {} --tool offset(s) were given",
                                     file->source, r.line, r.id, r.tool + 1, p.options.tool_offsets.size()));
      }
    }
  }
  p.noise = stage::TrackerNoise::Preset(args.tracker);
  p.weighted = !args.unweighted && !p.noise.IsNoiseFree();
  p.observations = artefacts::TrackerObservations(p.readings, p.weighted ? &p.noise : nullptr);
  if (p.validation) p.validation_observations = artefacts::TrackerObservations(*p.validation, nullptr);
  p.workspace = WorkspaceOf(args, p.readings, p.validation);
  p.basis = *stage::ParseBasis(args.basis);
  p.options.instrument = args.pose.empty() ? stage::InstrumentPose::kEstimated : stage::InstrumentPose::kHeld;
  if (!args.pose.empty()) p.options.pose = ParsePose(args.pose, "--pose");
  p.options.num_threads = ThreadCount();
  p.options.max_error_mm = args.max_error_mm;
  return p;
}

stage::VerificationResult VerifyProblem(const MachineProblem& problem, const stage::ParameterLayout& layout) {
  try {
    return stage::VerifyMachine(layout, problem.observations, problem.options);
  } catch (const std::invalid_argument& e) {
    throw VerificationRefusal(problem.readings.source, e);
  }
}

InputError VerificationRefusal(const std::string& source, const std::invalid_argument& refusal) {
  const bool implausible = dynamic_cast<const stage::ImplausibleFit*>(&refusal) != nullptr &&
                           dynamic_cast<const stage::DegenerateReadings*>(&refusal) == nullptr;
  return InputError(fmt::format("{}: {}{}", source, refusal.what(),
                                implausible ? " (a machine really this far out: raise the bound with --max-error-mm)" : ""));
}

std::string NotConvergedReason(const stage::IdentificationResult& identified) {
  const std::string& report = identified.solver_report;
  const size_t at = report.find("Termination: ");
  const std::string termination = at == std::string::npos ? std::string() : report.substr(at + 13, report.find_first_of(" ,\n", at + 13) - at - 13);
  const std::string advice = "the results are written but must not be trusted as they are: check the readings (units, "
                             "ids, outliers) or try a smaller model";
  if (termination == "NO_CONVERGENCE") {
    return fmt::format("the identification stopped at its limit of {} iterations before the fit settled; {}",
                       identified.iterations, advice);
  }
  return fmt::format("the identification failed after {} iterations ({}); {}", identified.iterations,
                     termination.empty() ? "the solver gave no reason" : "the solver ended with " + termination, advice);
}

nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm) {
  const double bound = max_error_mm > 0 ? max_error_mm : stage::DefaultMaxErrorMm(identified.calibration.layout);
  const stage::TermExcess largest = stage::LargestExcess(identified.calibration, bound);
  return {{"max_error_mm", bound},
          {"largest_term", largest.term >= 0 ? std::string(stage::GetErrorTerm(largest.term).vdi) : std::string()},
          {"largest_share", largest.share}};
}

nlohmann::json ErrorJson(const stage::VolumetricError& e) {
  return {{"mean_um", e.mean_um}, {"max_um", e.max_um}, {"min_um", e.min_um}};
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

void CheckTrackerSight(const MachineProblem& problem, const stage::Pose& pose) {
  // Points the tracker could not have seen from the pose found: a reading there is a mistake in the file.
  const std::vector<std::string> beyond = artefacts::PointsBeyondTrackerLimits(problem.readings, pose);
  if (!beyond.empty()) {
    throw InputError(fmt::format("{}: {} of {} readings lie outside the tracker's range or angle limits from the pose "
                                 "found (first: {}); check the file's units and columns",
                                 problem.readings.source, beyond.size(), problem.readings.points.size(), beyond.front()));
  }
}

}  // namespace fvm::cli
