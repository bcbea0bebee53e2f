#pragma once
// Tracker (or CMM) readings turned into an identification problem: the chain, tool offsets, weights, the travel the
// error functions are defined on, the instrument pose held or estimated, with the checks every machine-tool job
// shares (verify, uncertainty, tracker placement, test-piece verify). Refusals name the file, line and point, and
// the options as the command line spells them (--chain, --machine, --tool, --max-error-mm).

#include <Eigen/Core>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "artefacts/io/tracker_readings.h"
#include "artefacts/machine_truth.h"
#include "core/input_error.h"
#include "stage/identification.h"
#include "stage/machine_verification.h"
#include "stage/tracker.h"

namespace fvm::workflows {

struct MachineProblemOptions {
  std::string data;                   // readings: id,x,y,z + xt,yt,zt or range,azimuth,elevation (mm, rad)
  std::string validate;               // other readings to judge the model on (never fitted); empty: none
  std::string chain = "XFYZ";         // F notation: letters left of F move the part
  std::string basis = "legendre";     // power | legendre | chebyshev
  std::vector<Eigen::Vector3d> tools{Eigen::Vector3d::Zero()};  // tool offsets (mm); a `tool` column picks one
  std::optional<stage::Pose> pose;    // the tracker pose held; none: estimated jointly with the errors
  std::optional<artefacts::Workspace> travel;  // the axes' travel; none: the span of the commanded points
  std::string travel_name;            // how the travel was given, first in its refusal ("--machine '400x400x200'")
  std::string tracker = "published";  // noise preset (stage::TrackerNoise::PresetNames) for the weights
  bool unweighted = false;            // equal weights instead of the readings' covariances (their own or the tracker's)
  double max_error_mm = 0;            // plausibility bound; 0: 1 mm per metre of the longest travel
  int threads = 0;                    // 0: all cores
  // Refuses a basis, tracker preset or bound no job takes, and no tool, naming the option (--basis, --tracker, ...);
  // the chain and the files are checked as they are read (LoadMachineProblem).
  void Check() const;
};

struct MachineProblem {
  artefacts::TrackerReadings readings;
  std::optional<artefacts::TrackerReadings> validation;
  stage::AxisChain chain;                // tool offset: the first tool
  stage::IdentificationOptions options;  // tool offsets, instrument held or estimated, pose, threads
  stage::TrackerNoise noise;
  bool weighted = true;
  std::vector<stage::Observation> observations;             // the readings, weighted by their covariances when `weighted`
  std::vector<stage::Observation> validation_observations;  // unweighted; empty without validation readings
  artefacts::Workspace workspace;        // the travel given, or the span of the commanded points
  stage::Basis basis = stage::Basis::kLegendre;
  std::string WeightsName() const;       // "tracker published", "the readings' covariances" or "equal"
  stage::ParameterLayout Layout(int order) const;
};

// Reads and checks everything; bad input is an InputError naming the file, line and point.
MachineProblem LoadMachineProblem(const MachineProblemOptions& options);
// The same from readings already in memory (a script's arrays; refused as artefacts::CheckTrackerReadings says);
// options.data and options.validate are not read.
MachineProblem MakeMachineProblem(const MachineProblemOptions& options, artefacts::TrackerReadings readings,
                                  std::optional<artefacts::TrackerReadings> validation);

// Identifies `layout` (stage::VerifyMachine); a refusal is an InputError naming the data file (an implausible
// result says how to raise the bound).
stage::VerificationResult VerifyProblem(const MachineProblem& problem, const stage::ParameterLayout& layout);
// The InputError for a verification's refusal: the data file and the reason; for an implausible result
// (stage::ImplausibleFit) also how to raise the bound.
InputError VerificationRefusal(const std::string& source, const std::invalid_argument& refusal);
// What `identify` (a stage verification of the problem's readings) returns; its refusal as VerificationRefusal's.
template <typename Identify>
auto RefusalsNamingTheData(const MachineProblem& problem, Identify identify) -> decltype(identify()) {
  try {
    return identify();
  } catch (const std::invalid_argument& e) {
    throw VerificationRefusal(problem.readings.source, e);
  }
}
// Refuses readings the tracker could not have made from `pose` (artefacts/tracker_sight.h): a mistake in the file.
void CheckTrackerSight(const MachineProblem& problem, const stage::Pose& pose);

// The volumetric error of `observations` before (ideal machine, initial pose) and after (identified model and
// pose) a verification: held-out points judged by the model.
struct VolumetricChange {
  stage::ResidualSummary before, after;
};
VolumetricChange JudgeOn(const stage::VerificationResult& v, const std::vector<stage::Observation>& observations,
                         const std::vector<Eigen::Vector3d>& tools);

// The one-line reason an identification did not converge, for exit 3 ("the identification stopped at its limit of
// 100 iterations before the fit settled: ..."): what happened and what to try, without the solver's raw report.
std::string NotConvergedReason(const stage::IdentificationResult& identified);

}  // namespace fvm::workflows
