#include "stage/machine_verification.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/dense_decomposition.h"
#include "stage/plausibility.h"
#include "stage/residual_summary.h"

namespace fvm::stage {
namespace {

AxisChain ChainWithTool(const AxisChain& chain, const std::vector<Eigen::Vector3d>& tool_offsets, int tool) {
  AxisChain out = chain;
  if (!tool_offsets.empty()) out.tool_offset = tool_offsets.at(static_cast<size_t>(tool));
  return out;
}

}  // namespace

std::vector<Eigen::Vector3d> PredictedReadings(const ParameterLayout& layout, const std::vector<double>* values,
                                               const Pose& pose, const std::vector<Observation>& points,
                                               const std::vector<Eigen::Vector3d>& tool_offsets) {
  std::vector<double> all(layout.coefficients().size(), 0.0);
  if (values != nullptr) layout.Expand(values->data(), all.data());
  const double pose6[6] = {pose.translation[0], pose.translation[1], pose.translation[2],
                           pose.rotation[0],    pose.rotation[1],    pose.rotation[2]};
  std::vector<AxisChain> chains;
  for (size_t t = 0; t < std::max<size_t>(1, tool_offsets.size()); ++t) {
    chains.push_back(ChainWithTool(layout.chain(), tool_offsets, static_cast<int>(t)));
  }
  std::vector<Eigen::Vector3d> predicted;
  predicted.reserve(points.size());
  for (const Observation& o : points) {
    double e[kNumErrorTerms];
    layout.TermValues(all.data(), o.command, e);
    predicted.push_back(ChainForward(chains.at(static_cast<size_t>(o.tool)), e, o.command, pose6));
  }
  return predicted;
}

std::vector<Eigen::Vector3d> VolumetricResiduals(const ParameterLayout& layout, const std::vector<double>* values,
                                                 const Pose& pose, const std::vector<Observation>& readings,
                                                 const std::vector<Eigen::Vector3d>& tool_offsets) {
  std::vector<Eigen::Vector3d> residuals = PredictedReadings(layout, values, pose, readings, tool_offsets);
  for (size_t i = 0; i < residuals.size(); ++i) residuals[i] -= readings[i].measured;
  return residuals;
}

Pose RigidStartPose(const AxisChain& chain, const std::vector<Observation>& readings,
                    const std::vector<Eigen::Vector3d>& tool_offsets) {
  const Eigen::Index m = static_cast<Eigen::Index>(readings.size());
  Eigen::Matrix3Xd tracker(3, m), part(3, m);
  const double zero[kNumErrorTerms] = {};
  for (Eigen::Index i = 0; i < m; ++i) {
    const Observation& o = readings[static_cast<size_t>(i)];
    tracker.col(i) = o.measured;
    part.col(i) = ChainForward(ChainWithTool(chain, tool_offsets, o.tool), zero, o.command);
  }
  // The points must span three dimensions, or the rotation about their line or plane is free.
  const Eigen::Matrix3Xd centred = part.colwise() - part.rowwise().mean();
  const auto svd = Decompose<Eigen::JacobiSVD<Eigen::Matrix3Xd>>(centred, "the tracker pose: the spread of the points");
  if (m < 3 || svd.singularValues()[2] < 1e-6 * std::max(svd.singularValues()[0], 1e-300)) {
    throw std::invalid_argument("the points lie on a line or a plane: the tracker pose cannot be found from them");
  }
  // part = R tracker + t is the pose (ToPosedFrame inverts it).
  const Eigen::Matrix4d transform = Eigen::umeyama(tracker, part, false);
  Pose pose;
  pose.translation = transform.block<3, 1>(0, 3);
  const Eigen::AngleAxisd angle_axis(Eigen::Matrix3d(transform.block<3, 3>(0, 0)));
  pose.rotation = angle_axis.angle() * angle_axis.axis();
  return pose;
}

VerificationResult VerifyMachine(const ParameterLayout& layout, const std::vector<Observation>& readings,
                                 IdentificationOptions options) {
  if (options.instrument == InstrumentPose::kNone) {
    throw std::invalid_argument("a verification needs the tracker pose: held or estimated");
  }
  // With too few readings for the model, Identify's count says what to do; otherwise their span first.
  if (3 * readings.size() >= static_cast<size_t>(layout.NumFree()) + 6) CheckReadingsSpan(layout, readings, options.tool_offsets);
  if (options.instrument == InstrumentPose::kEstimated && options.pose.translation.isZero() && options.pose.rotation.isZero()) {
    options.pose = RigidStartPose(layout.chain(), readings, options.tool_offsets);
  }
  // Before: the ideal machine, in the pose that fits it best (or the held one).
  Pose initial_pose = options.pose;
  if (options.instrument == InstrumentPose::kEstimated) {
    const ParameterLayout ideal(layout.chain(), layout.travel());
    IdentificationOptions ideal_options = options;
    ideal_options.on_iteration = nullptr;  // the caller logs the verification, not the search for its start
    initial_pose = Identify(ideal, readings, ideal_options).pose;
    options.pose = initial_pose;
  }
  VerificationResult result(Identify(layout, readings, options));
  CheckPlausibleMachine(result.identified, options.max_error_mm);
  result.initial_pose = initial_pose;
  result.initial = Summarize(VolumetricResiduals(layout, nullptr, initial_pose, readings, options.tool_offsets));
  result.final = Summarize(result.identified.residuals);
  return result;
}

ParameterLayout MachineLayout(const AxisChain& chain, const std::array<Travel, 3>& travel, Basis basis, int order) {
  ParameterLayout layout(chain, travel);
  for (const char* axis : {"x", "y", "z"}) {
    for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"}) layout.SetTerm(std::string(axis) + kind, basis, order);
  }
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, basis, 0);
  return layout;
}

}  // namespace fvm::stage
