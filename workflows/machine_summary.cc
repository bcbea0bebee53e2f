#include "workflows/machine_summary.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <cmath>

#include "stage/error_terms.h"
#include "stage/io/calibration_file.h"
#include "stage/plausibility.h"

namespace fvm::workflows {
namespace {

// A pose as people read it: the XYZ Euler angles (deg) next to the rotation vector, and the standard uncertainties
// of translation (um) and rotation vector (urad) when a covariance is given.
struct PoseNumbers {
  Eigen::Vector3d euler_deg;
  std::optional<Eigen::Matrix<double, 6, 1>> u;  // mm and rad
};

PoseNumbers NumbersOf(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance) {
  PoseNumbers n{EulerXyzDeg(pose), std::nullopt};
  if (covariance != nullptr) n.u = covariance->diagonal().cwiseMax(0.0).cwiseSqrt();
  return n;
}

// Before (ideal machine, initial pose) and after (identified model and pose) volumetric error of each reading.
std::vector<report::MachineReportData::PointError> PointErrors(const stage::VerificationResult& v,
                                                               const std::vector<stage::Observation>& observations,
                                                               const std::vector<Eigen::Vector3d>& tools) {
  const stage::Calibration& cal = v.identified.calibration;
  const std::vector<Eigen::Vector3d> before =
      stage::VolumetricResiduals(cal.layout, nullptr, v.initial_pose, observations, tools);
  const std::vector<Eigen::Vector3d> after =
      stage::VolumetricResiduals(cal.layout, &cal.values, v.identified.pose, observations, tools);
  std::vector<report::MachineReportData::PointError> out;
  for (size_t i = 0; i < observations.size(); ++i) {
    const Eigen::Vector3d& q = observations[i].command;
    out.push_back({q.x(), q.y(), q.z(), before[i].norm() * 1e3, after[i].norm() * 1e3});
  }
  return out;
}

std::string ErrorText(const stage::ResidualSummary& e) {
  return fmt::format("max {:.1f} / mean {:.1f} / min {:.1f} um", e.max_um(), e.mean_um(), e.min_um());
}

// The 21 error functions over each axis' travel, relative to their value at the axis' origin, with u.
void SampleFunctions(const stage::Calibration& cal, const Eigen::Vector3d& origin, report::MachineReportData& data) {
  constexpr int kSamples = 101;
  for (int k = 0; k < 3; ++k) {
    report::MachineReportData::AxisFunctions& f = data.functions[static_cast<size_t>(k)];
    f.axis = std::string(1, "XYZ"[k]);
    const stage::Travel travel = cal.layout.travel()[static_cast<size_t>(k)];
    const stage::Axis axis = static_cast<stage::Axis>(k);
    for (int c = 0; c < 3; ++c) {
      f.translations.push_back({std::string(stage::GetErrorTerm(stage::TranslationTerm(axis, c)).vdi), {}, {}});
      f.rotations.push_back({std::string(stage::GetErrorTerm(stage::RotationTerm(axis, c)).vdi), {}, {}});
    }
    for (int i = 0; i < kSamples; ++i) {
      Eigen::Vector3d q = origin;
      q[k] = travel.min + (travel.max - travel.min) * i / (kSamples - 1);
      f.position_mm.push_back(q[k]);
      const stage::TermValuesWithUncertainty t = stage::TermValuesAt(cal, q, &origin);
      for (int c = 0; c < 3; ++c) {
        const int tt = stage::TranslationTerm(axis, c), rt = stage::RotationTerm(axis, c);
        f.translations[static_cast<size_t>(c)].value.push_back(t.value[tt] * 1e3);
        f.translations[static_cast<size_t>(c)].u.push_back(t.u[tt] * 1e3);
        f.rotations[static_cast<size_t>(c)].value.push_back(t.value[rt] * 1e6);
        f.rotations[static_cast<size_t>(c)].u.push_back(t.u[rt] * 1e6);
      }
    }
  }
}

report::MachineReportData::Table SquarenessTable(const stage::Calibration& cal, const Eigen::Vector3d& origin) {
  report::MachineReportData::Table squareness{
      "Squareness", "Constant angles; U is the expanded uncertainty (k = 2).", {"term", "value (urad)", "U (urad)"}, {}};
  const stage::TermValuesWithUncertainty at_origin = stage::TermValuesAt(cal, origin);
  for (int w = 0; w < 3; ++w) {
    const int t = stage::kFirstSquarenessTerm + w;
    squareness.rows.push_back({std::string(stage::GetErrorTerm(t).vdi), fmt::format("{:.2f}", at_origin.value[t] * 1e6),
                               fmt::format("{:.2f}", 2 * at_origin.u[t] * 1e6)});
  }
  return squareness;
}

report::MachineReportData::Table PoseTable(const stage::IdentificationResult& r, bool held) {
  const PoseNumbers n = NumbersOf(r.pose, held ? nullptr : &r.pose_covariance);
  report::MachineReportData::Table pose{
      "Tracker pose",
      fmt::format("{} in the machine frame; u is the standard uncertainty.",
                  held ? "Held (--pose)" : "Estimated jointly with the errors"),
      {"", "x", "y", "z"},
      {}};
  const auto triple = [&](const char* what, const Eigen::Vector3d& values, const char* format) {
    std::vector<std::string> row{what};
    for (int i = 0; i < 3; ++i) row.push_back(fmt::format(fmt::runtime(format), values[i]));
    pose.rows.push_back(row);
  };
  triple("translation (mm)", r.pose.translation, "{:.4f}");
  if (n.u) triple("u translation (um)", n.u->head<3>() * 1e3, "{:.1f}");
  triple("XYZ Euler angles (deg)", n.euler_deg, "{:.5f}");
  triple("rotation vector (rad)", r.pose.rotation, "{:.7f}");
  if (n.u) triple("u rotation vector (urad)", n.u->tail<3>() * 1e6, "{:.1f}");
  return pose;
}

}  // namespace

Eigen::Vector3d EulerXyzDeg(const stage::Pose& pose) { return pose.Rotation().eulerAngles(0, 1, 2) * 180.0 / M_PI; }

nlohmann::json ErrorJson(const stage::ResidualSummary& e) {
  return {{"mean_um", e.mean_um()}, {"max_um", e.max_um()}, {"min_um", e.min_um()}};
}

nlohmann::json PoseJson(const stage::Pose& pose, const Eigen::Matrix<double, 6, 6>* covariance) {
  const PoseNumbers n = NumbersOf(pose, covariance);
  nlohmann::json j{{"translation_mm", {pose.translation.x(), pose.translation.y(), pose.translation.z()}},
                   {"rotation_vector_rad", {pose.rotation.x(), pose.rotation.y(), pose.rotation.z()}},
                   {"euler_xyz_deg", {n.euler_deg.x(), n.euler_deg.y(), n.euler_deg.z()}}};
  if (n.u) {
    const Eigen::Matrix<double, 6, 1>& u = *n.u;
    j["u_translation_um"] = {u[0] * 1e3, u[1] * 1e3, u[2] * 1e3};
    j["u_rotation_urad"] = {u[3] * 1e6, u[4] * 1e6, u[5] * 1e6};
  }
  return j;
}

nlohmann::json PlausibilityJson(const stage::IdentificationResult& identified, double max_error_mm) {
  const double bound = max_error_mm > 0 ? max_error_mm : stage::DefaultMaxErrorMm(identified.calibration.layout);
  const stage::TermExcess largest = stage::LargestExcess(identified.calibration, bound);
  return {{"max_error_mm", bound},
          {"largest_term", largest.term >= 0 ? std::string(stage::GetErrorTerm(largest.term).vdi) : std::string()},
          {"largest_share", largest.share}};
}

nlohmann::json VerificationJson(const MachineProblem& problem, const MachineProblemOptions& options, int order,
                                const stage::VerificationResult& v, const std::optional<VolumetricChange>& validation) {
  const stage::IdentificationResult& r = v.identified;
  nlohmann::json doc;
  doc["chain"] = problem.chain.code;
  doc["basis"] = options.basis;
  doc["order"] = order;
  doc["points"] = problem.readings.points.size();
  doc["weights"] = problem.WeightsName();
  doc["initial"] = ErrorJson(v.initial);
  doc["final"] = ErrorJson(v.final);
  doc["final"]["rms_um"] = r.residual_summary.rms_um();
  if (problem.weighted) doc["final"]["weighted_rms"] = r.weighted_rms;
  if (validation) {
    doc["validation"] = {{"points", problem.validation->points.size()},
                         {"initial", ErrorJson(validation->before)},
                         {"final", ErrorJson(validation->after)}};
  }
  const bool held = options.pose.has_value();
  doc["pose"] = PoseJson(r.pose, held ? nullptr : &r.pose_covariance);
  doc["pose"]["estimated"] = !held;
  doc["pose"]["initial"] = PoseJson(v.initial_pose, nullptr);
  const nlohmann::json calibration = stage::CalibrationToJson(r);
  doc["fixed"] = calibration["fixed"];
  doc["parameters"] = calibration["parameters"];
  doc["plausibility"] = PlausibilityJson(r, options.max_error_mm);
  doc["converged"] = r.converged;
  if (!r.converged) doc["solver_report"] = r.solver_report;
  return doc;
}

report::MachineReportData VerificationReport(const std::string& title, const std::string& weights,
                                             const MachineProblem& problem, const stage::VerificationResult& v,
                                             const std::optional<VolumetricChange>& validation) {
  const stage::IdentificationResult& r = v.identified;
  const stage::Calibration& cal = r.calibration;
  report::MachineReportData data;
  data.title = title;
  data.summary = {{"points", fmt::format("{} ({} weights)", problem.observations.size(), weights)},
                  {"volumetric error, initial", ErrorText(v.initial)},
                  {"volumetric error, final", ErrorText(v.final)}};
  if (validation) {
    data.summary.push_back({fmt::format("validation ({} points), initial", problem.validation_observations.size()),
                            ErrorText(validation->before)});
    data.summary.push_back({"validation, final", ErrorText(validation->after)});
  }
  data.summary.push_back({"free coefficients", fmt::format("{} ({} fixed)", cal.layout.NumFree(), r.fixed.size())});
  data.summary.push_back({"converged", r.converged ? "yes" : "no"});

  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = cal.layout.travel()[static_cast<size_t>(k)].min;
  SampleFunctions(cal, origin, data);
  data.tables.push_back(SquarenessTable(cal, origin));
  data.tables.push_back(PoseTable(r, problem.options.instrument == stage::InstrumentPose::kHeld));
  report::MachineReportData::Table fixed{"Terms the data cannot separate",
                                         "Fixed at zero before the fit, each with the combination of other parameters "
                                         "that has the same effect on these readings (the pose absorbs constants; "
                                         "aliases share one effect).",
                                         {"coefficient", "reason"},
                                         {}};
  for (const stage::FixedCoefficient& f : r.fixed) fixed.rows.push_back({f.name, f.reason});
  data.tables.push_back(fixed);

  data.readings = PointErrors(v, problem.observations, problem.options.tool_offsets);
  if (validation) data.validation = PointErrors(v, problem.validation_observations, problem.options.tool_offsets);
  return data;
}

}  // namespace fvm::workflows
