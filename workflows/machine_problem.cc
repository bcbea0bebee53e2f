#include "workflows/machine_problem.h"

#include <fmt/core.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <limits>

#include "artefacts/tracker_observations.h"
#include "artefacts/tracker_sight.h"
#include "stage/plausibility.h"

namespace fvm::workflows {
namespace {

// A coordinate as a message shows it (the command line's ReadableNumber: six significant digits).
std::string Readable(double mm) { return fmt::format("{:.6g}", mm); }

// The travel given must hold every commanded point: the polynomial bases are defined on the travel only (Legendre
// and Chebyshev on [-1, 1]); far outside it their powers mean nothing, and overflow.
void CheckInsideTravel(const MachineProblemOptions& options, const artefacts::Workspace& ws,
                       const artefacts::TrackerReadings& readings) {
  constexpr double kToleranceMm = 1e-3;
  for (const artefacts::TrackerReading& r : readings.points) {
    for (int k = 0; k < 3; ++k) {
      if (r.nominal[k] < ws.min[k] - kToleranceMm || r.nominal[k] > ws.max[k] + kToleranceMm) {
        throw InputError(fmt::format(
            "{}: {}:{}: point {} has {} = {} mm, outside the declared {} travel {} .. {} mm; give travels "
            "that hold every point (LXxLYxLZ@X0,Y0,Z0), or leave --machine out to take the span of the points",
            options.travel_name, readings.source, r.line, r.id, "xyz"[k], Readable(r.nominal[k]), "XYZ"[k],
            Readable(ws.min[k]), Readable(ws.max[k])));
      }
    }
  }
}

// The workspace the error functions are defined on: the travel given, or the span of the commanded points.
artefacts::Workspace WorkspaceOf(const MachineProblemOptions& options, const artefacts::TrackerReadings& readings,
                                 const std::optional<artefacts::TrackerReadings>& validation) {
  if (options.travel) {
    const artefacts::Workspace& ws = *options.travel;
    CheckInsideTravel(options, ws, readings);
    if (validation) CheckInsideTravel(options, ws, *validation);
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

void MachineProblemOptions::Check() const {
  if (!stage::ParseBasis(basis)) throw InputError(fmt::format("--basis {}: use power, legendre or chebyshev", basis));
  const std::vector<std::string> presets = stage::TrackerNoise::PresetNames();
  if (std::find(presets.begin(), presets.end(), tracker) == presets.end()) {
    throw InputError(fmt::format("--tracker {}: use one of {}", tracker, fmt::join(presets, ", ")));
  }
  if (tools.empty()) throw InputError("no tool offset: give at least one (--tool X,Y,Z, mm)");
  if (!(max_error_mm >= 0)) throw InputError(fmt::format("--max-error-mm {}: give a bound > 0 mm (0: the default)", max_error_mm));
  if (threads < 0) throw InputError(fmt::format("--threads {}: give 0 (all cores) or more", threads));
}

std::string MachineProblem::WeightsName() const {
  if (!weighted) return "equal";
  return artefacts::CarriesCovariances(readings) ? "the readings' covariances" : "tracker " + noise.name;
}

stage::ParameterLayout MachineProblem::Layout(int order) const {
  std::array<stage::Travel, 3> travel;
  for (int k = 0; k < 3; ++k) travel[static_cast<size_t>(k)] = stage::Travel{workspace.min[k], workspace.max[k]};
  return stage::MachineLayout(chain, travel, basis, order);
}

MachineProblem LoadMachineProblem(const MachineProblemOptions& o) {
  std::optional<artefacts::TrackerReadings> validation;
  artefacts::TrackerReadings readings = artefacts::ReadTrackerReadings(o.data);
  if (!o.validate.empty()) validation = artefacts::ReadTrackerReadings(o.validate);
  return MakeMachineProblem(o, std::move(readings), std::move(validation));
}

MachineProblem MakeMachineProblem(const MachineProblemOptions& o, artefacts::TrackerReadings readings,
                                  std::optional<artefacts::TrackerReadings> validation) {
  MachineProblem p;
  p.readings = std::move(readings);
  p.validation = std::move(validation);
  // What a reader refuses in a file, refused in readings made in memory too (a file's pass again, cheaply).
  artefacts::CheckTrackerReadings(p.readings, p.readings.source);
  if (p.validation) artefacts::CheckTrackerReadings(*p.validation, p.validation->source);
  try {
    p.chain = stage::AxisChain::Parse(o.chain);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("--chain {}: {}", o.chain, e.what()));
  }
  if (o.tools.empty()) throw InputError("no tool offset: give at least one (--tool X,Y,Z, mm)");
  p.options.tool_offsets = o.tools;
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
  p.noise = stage::TrackerNoise::Preset(o.tracker);
  // Readings that carry their own covariance (multilaterated points: all or none) are weighed by it.
  p.weighted = !o.unweighted && (artefacts::CarriesCovariances(p.readings) || !p.noise.IsNoiseFree());
  p.observations = artefacts::TrackerObservations(p.readings, p.weighted ? &p.noise : nullptr);
  if (p.validation) p.validation_observations = artefacts::TrackerObservations(*p.validation, nullptr);
  p.workspace = WorkspaceOf(o, p.readings, p.validation);
  p.basis = *stage::ParseBasis(o.basis);
  p.options.instrument = o.pose ? stage::InstrumentPose::kHeld : stage::InstrumentPose::kEstimated;
  if (o.pose) p.options.pose = *o.pose;
  p.options.num_threads = o.threads;
  p.options.max_error_mm = o.max_error_mm;
  return p;
}

stage::VerificationResult VerifyProblem(const MachineProblem& problem, const stage::ParameterLayout& layout) {
  return RefusalsNamingTheData(problem, [&] { return stage::VerifyMachine(layout, problem.observations, problem.options); });
}

InputError VerificationRefusal(const std::string& source, const std::invalid_argument& refusal) {
  const bool implausible = dynamic_cast<const stage::ImplausibleFit*>(&refusal) != nullptr &&
                           dynamic_cast<const stage::DegenerateReadings*>(&refusal) == nullptr;
  return InputError(fmt::format("{}: {}{}", source, refusal.what(),
                                implausible ? " (a machine really this far out: raise the bound with --max-error-mm)" : ""));
}

VolumetricChange JudgeOn(const stage::VerificationResult& v, const std::vector<stage::Observation>& observations,
                         const std::vector<Eigen::Vector3d>& tools) {
  const stage::Calibration& cal = v.identified.calibration;
  return {stage::Summarize(stage::VolumetricResiduals(cal.layout, nullptr, v.initial_pose, observations, tools)),
          stage::Summarize(
              stage::VolumetricResiduals(cal.layout, &cal.values, v.identified.pose, observations, tools))};
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

void CheckTrackerSight(const MachineProblem& problem, const stage::Pose& pose) {
  // Points the tracker could not have seen from the pose found: a reading there is a mistake in the file.
  const std::vector<std::string> beyond = artefacts::PointsBeyondTrackerLimits(problem.readings, pose);
  if (!beyond.empty()) {
    throw InputError(fmt::format("{}: {} of {} readings lie outside the tracker's range or angle limits from the pose "
                                 "found (first: {}); check the file's units and columns",
                                 problem.readings.source, beyond.size(), problem.readings.points.size(), beyond.front()));
  }
}

}  // namespace fvm::workflows
