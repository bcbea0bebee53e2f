#pragma once
// Volumetric verification of a machine tool from laser-tracker readings ([Aguado 2016], [IJSIMM 2016], [Pérez 2017]):
// identify the 21 error functions and the tracker pose from the readings at commanded points, and say how far the
// machine is from where it should be before and after.
//
// Volumetric error = distance between a tracker reading and the model's prediction of the ideal machine (before)
// or of the identified machine (after), in the tracker frame. Before, the pose is that of the ideal machine's best
// fit to the readings (or the held pose); after, the jointly estimated one. Error functions vanish at the origin of
// their axis only up to what the pose absorbs: a rigid best fit alone cannot supply the pose, so it is estimated
// jointly with the errors by default, and the rank treatment names the constant terms it absorbs.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "stage/identification.h"
#include "stage/residual_summary.h"

namespace fvm::stage {

struct VerificationResult {
  explicit VerificationResult(IdentificationResult r) : identified(std::move(r)) {}
  IdentificationResult identified;  // the error model and the final pose (identified.pose)
  Pose initial_pose;                // the pose the initial error is stated in
  ResidualSummary initial, final;  // the volumetric errors before and after
};

// The layout `fvm verify` identifies: the 18 translation and rotation terms of `chain` as polynomials of `order` in
// `basis` over `travel`, and the three squareness terms as constants.
ParameterLayout MachineLayout(const AxisChain& chain, const std::array<Travel, 3>& travel, Basis basis, int order);

// The rigid pose that maps readings onto the ideal machine's tool points (closed-form least squares, [Umeyama 1991]):
// a start for the joint estimate. Throws std::invalid_argument when the points do not span three dimensions.
Pose RigidStartPose(const AxisChain& chain, const std::vector<Observation>& readings,
                    const std::vector<Eigen::Vector3d>& tool_offsets = {});

// Identifies `layout` from the readings. options.instrument must be kHeld or kEstimated; with kEstimated,
// options.pose is only where the search starts (RigidStartPose when left at zero). Refuses (ImplausibleFit,
// stage/plausibility.h) readings that do not span the commanded points, and a result with an error term or a
// residual beyond options.max_error_mm.
VerificationResult VerifyMachine(const ParameterLayout& layout, const std::vector<Observation>& readings,
                                 IdentificationOptions options);

// The tracker-frame tool points that `layout` with free coefficients `values` (null: the ideal machine) at `pose`
// predicts for the commands (and tools) of `points`.
std::vector<Eigen::Vector3d> PredictedReadings(const ParameterLayout& layout, const std::vector<double>* values,
                                               const Pose& pose, const std::vector<Observation>& points,
                                               const std::vector<Eigen::Vector3d>& tool_offsets = {});

// PredictedReadings - reading in the tracker frame for each reading: the ideal machine when `values` is null.
std::vector<Eigen::Vector3d> VolumetricResiduals(const ParameterLayout& layout, const std::vector<double>* values,
                                                 const Pose& pose, const std::vector<Observation>& readings,
                                                 const std::vector<Eigen::Vector3d>& tool_offsets = {});

}  // namespace fvm::stage
