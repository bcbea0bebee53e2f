#include "stage/validation.h"

#include <cmath>
#include <map>

namespace fvm::stage {
namespace {

Eigen::Vector3d Compensated(const Calibration* calibration, const Eigen::Vector3d& q, Eigen::MatrixXd* jacobian) {
  if (calibration == nullptr) return q;
  Eigen::Vector3d p;
  const Eigen::MatrixXd j = ForwardJacobian(calibration->layout, calibration->values.data(), q, &p);
  if (jacobian) *jacobian = j;
  return p;
}

}  // namespace

ResidualSummary Summarize(const std::vector<Eigen::Vector3d>& residuals) {
  ResidualSummary s;
  s.count = static_cast<int>(residuals.size());
  double sum = 0, sum_sq = 0;
  s.min_mm = residuals.empty() ? 0.0 : residuals.front().norm();
  for (const Eigen::Vector3d& r : residuals) {
    sum += r.norm();
    sum_sq += r.squaredNorm();
    s.max_mm = std::max(s.max_mm, r.norm());
    s.min_mm = std::min(s.min_mm, r.norm());
  }
  if (s.count > 0) {
    s.mean_mm = sum / s.count;
    s.rms_mm = std::sqrt(sum_sq / s.count);
  }
  return s;
}

ValidationStats Validate(const Calibration* calibration, const std::vector<Observation>& observations,
                         const std::vector<Eigen::Vector3d>& anchors) {
  ValidationStats stats;
  double predicted_sq = 0;
  for (const Observation& o : observations) {
    Eigen::MatrixXd jq, ja;
    Eigen::Vector3d r = Compensated(calibration, o.command, &jq) - o.measured;
    if (!anchors.empty()) {
      const Eigen::Vector3d& a = anchors.at(static_cast<size_t>(o.group));
      r -= Compensated(calibration, a, &ja) - a;
    }
    stats.residuals.push_back(r);
    if (calibration != nullptr && calibration->covariance.size() > 0) {
      const Eigen::MatrixXd d = anchors.empty() ? jq : Eigen::MatrixXd(jq - ja);
      predicted_sq += (d * calibration->covariance * d.transpose()).trace() + 3 * calibration->sigma_mm * calibration->sigma_mm;
    }
  }
  static_cast<ResidualSummary&>(stats) = Summarize(stats.residuals);
  if (stats.count > 0) stats.predicted_rms_mm = std::sqrt(predicted_sq / stats.count);
  return stats;
}

std::vector<double> DistanceErrors(const Calibration* calibration, const std::vector<Observation>& observations) {
  std::map<int, const Observation*> first;
  std::vector<double> errors;
  for (const Observation& o : observations) {
    const auto [it, inserted] = first.emplace(o.group, &o);
    if (inserted) continue;
    const Observation& f = *it->second;
    const double compensated = (Compensated(calibration, o.command, nullptr) - Compensated(calibration, f.command, nullptr)).norm();
    errors.push_back(compensated - (o.measured - f.measured).norm());
  }
  return errors;
}

}  // namespace fvm::stage
