// The report of a verification (fvm verify, fvm testpiece verify): the error functions sampled over each axis' travel
// relative to the axis' origin, with u from the covariance; the squareness, pose and fixed-term tables; the error
// of every point before and after.

#include <fmt/core.h>

#include "fvm/machine_problem.h"
#include "stage/calibration.h"
#include "stage/error_terms.h"

namespace fvm::cli {
namespace {

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

std::vector<std::string> Row(std::initializer_list<std::string> cells) { return cells; }

}  // namespace

report::MachineReportData MachineVerificationReport(const MachineArgs& args, const nlohmann::json& doc, const stage::VerificationResult& v,
                                            const std::vector<stage::Observation>& observations,
                                            const std::vector<stage::Observation>* validation,
                                            const std::vector<Eigen::Vector3d>& tools) {
  const stage::IdentificationResult& r = v.identified;
  const stage::Calibration& cal = r.calibration;
  report::MachineReportData data;
  data.title = fmt::format("fvm verify: {} order {} ({}) on {}", doc["chain"].get<std::string>(), doc["order"].get<int>(),
                           args.basis, args.data);
  const auto errors = [](const nlohmann::json& e) {
    return fmt::format("max {:.1f} / mean {:.1f} / min {:.1f} um", e["max_um"].get<double>(), e["mean_um"].get<double>(),
                       e["min_um"].get<double>());
  };
  data.summary = {{"points", fmt::format("{} ({} weights)", observations.size(), doc["weights"].get<std::string>())},
                  {"volumetric error, initial", errors(doc["initial"])},
                  {"volumetric error, final", errors(doc["final"])}};
  if (validation != nullptr) {
    data.summary.push_back({fmt::format("validation ({} points), initial", validation->size()), errors(doc["validation"]["initial"])});
    data.summary.push_back({"validation, final", errors(doc["validation"]["final"])});
  }
  data.summary.push_back({"free coefficients", fmt::format("{} ({} fixed)", cal.layout.NumFree(), r.fixed.size())});
  data.summary.push_back({"converged", r.converged ? "yes" : "no"});

  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = cal.layout.travel()[static_cast<size_t>(k)].min;
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

  report::MachineReportData::Table squareness{"Squareness", "Constant angles; U is the expanded uncertainty (k = 2).",
                                      {"term", "value (urad)", "U (urad)"}, {}};
  const stage::TermValuesWithUncertainty at_origin = stage::TermValuesAt(cal, origin);
  for (int w = 0; w < 3; ++w) {
    const int t = stage::kFirstSquarenessTerm + w;
    squareness.rows.push_back(Row({std::string(stage::GetErrorTerm(t).vdi), fmt::format("{:.2f}", at_origin.value[t] * 1e6),
                                   fmt::format("{:.2f}", 2 * at_origin.u[t] * 1e6)}));
  }
  data.tables.push_back(squareness);

  const nlohmann::json& p = doc["pose"];
  report::MachineReportData::Table pose{"Tracker pose",
                                fmt::format("{} in the machine frame; u is the standard uncertainty.",
                                            p["estimated"].get<bool>() ? "Estimated jointly with the errors" : "Held (--pose)"),
                                {"", "x", "y", "z"}, {}};
  const auto triple = [&](const char* what, const nlohmann::json& values, const char* format) {
    std::vector<std::string> row{what};
    for (int i = 0; i < 3; ++i) row.push_back(fmt::format(fmt::runtime(format), values[static_cast<size_t>(i)].get<double>()));
    pose.rows.push_back(row);
  };
  triple("translation (mm)", p["translation_mm"], "{:.4f}");
  if (p.contains("u_translation_um")) triple("u translation (um)", p["u_translation_um"], "{:.1f}");
  triple("XYZ Euler angles (deg)", p["euler_xyz_deg"], "{:.5f}");
  triple("rotation vector (rad)", p["rotation_vector_rad"], "{:.7f}");
  if (p.contains("u_rotation_urad")) triple("u rotation vector (urad)", p["u_rotation_urad"], "{:.1f}");
  data.tables.push_back(pose);

  report::MachineReportData::Table fixed{"Terms the data cannot separate",
                                 "Fixed at zero before the fit, each with the combination of other parameters that has the "
                                 "same effect on these readings (the pose absorbs constants; aliases share one effect).",
                                 {"coefficient", "reason"}, {}};
  for (const stage::FixedCoefficient& f : r.fixed) fixed.rows.push_back(Row({f.name, f.reason}));
  data.tables.push_back(fixed);

  data.readings = PointErrors(v, observations, tools);
  if (validation != nullptr) data.validation = PointErrors(v, *validation, tools);
  return data;
}

}  // namespace fvm::cli
