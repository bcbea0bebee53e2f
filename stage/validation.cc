#include "stage/validation.h"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <cmath>
#include <map>
#include <optional>

#include "core/dense_decomposition.h"
#include "stage/undetermined_spread.h"

namespace fvm::stage {
namespace {

Eigen::Vector3d Compensated(const Calibration* calibration, const Eigen::Vector3d& q, Eigen::MatrixXd* jacobian) {
  if (calibration == nullptr) return q;
  Eigen::Vector3d p;
  const Eigen::MatrixXd j = ForwardJacobian(calibration->layout, calibration->values.data(), q, &p);
  if (jacobian) *jacobian = j;
  return p;
}

// The frame each measurement is turned in under the calibration: the rotated one only where the model's own rotation
// terms turn it (TurnCoefficients); otherwise the translated one, since only the model can turn it.
StitchedFrame ModelFrame(const Calibration& calibration, const std::vector<Eigen::Vector3d>& anchors, StitchedFrame frame) {
  const bool turned = frame == StitchedFrame::kRotated && !anchors.empty() && !TurnCoefficients(calibration.layout).empty();
  return turned ? frame : StitchedFrame::kTranslated;
}

// Each placement's first-tile compensation under the calibration, in `model_frame` (none without anchors).
std::vector<FirstTileCompensation> FirstTileFrames(const Calibration& calibration, const std::vector<Eigen::Vector3d>& anchors,
                                                   StitchedFrame model_frame) {
  std::vector<FirstTileCompensation> frames;
  for (const Eigen::Vector3d& a : anchors) frames.emplace_back(calibration, model_frame, a);
  return frames;
}

// The calibration's prediction of `o` and its Jacobian: in its placement's first-tile frame, or the stage's without.
Eigen::Vector3d Predicted(const Calibration& calibration, const std::vector<FirstTileCompensation>& frames,
                          const Observation& o, Eigen::MatrixXd* jacobian) {
  return frames.empty() ? Compensated(&calibration, o.command, jacobian) : frames.at(static_cast<size_t>(o.group))(o.command, jacobian);
}

}  // namespace

ValidationStats Validate(const Calibration* calibration, const std::vector<Observation>& observations,
                         const std::vector<Eigen::Vector3d>& anchors, StitchedFrame frame) {
  ValidationStats stats;
  const bool modelled = calibration != nullptr;
  const bool covariance = modelled && calibration->covariance.size() > 0;
  if (modelled && frame == StitchedFrame::kRotated && !anchors.empty()) {
    stats.turn_coefficients = TurnCoefficients(calibration->layout);
    stats.turn = stats.turn_coefficients.empty() ? "uncertainty" : "model";
  }
  const std::vector<FirstTileCompensation> frames =
      modelled ? FirstTileFrames(*calibration, anchors, ModelFrame(*calibration, anchors, frame)) : std::vector<FirstTileCompensation>{};
  std::vector<double> predicted_sq;
  std::vector<Eigen::Vector3d> arms;  // s - a, for the turn the model does not tell
  for (const Observation& o : observations) {
    Eigen::MatrixXd j;
    Eigen::Vector3d r;
    if (!modelled) {
      r = o.command - o.measured;  // no compensation: the first tile's own error is zero, whatever the frame
    } else {
      r = Predicted(*calibration, frames, o, &j) - o.measured;
    }
    if (!anchors.empty()) arms.push_back(o.measured - anchors.at(static_cast<size_t>(o.group)));
    stats.residuals.push_back(r);
    if (modelled) {
      stats.jacobians.push_back(j);
      predicted_sq.push_back((covariance ? (j * calibration->covariance * j.transpose()).trace() : 0.0) +
                             3 * calibration->sigma_mm * calibration->sigma_mm);
    }
  }
  if (modelled && frame == StitchedFrame::kRotated && !anchors.empty()) {
    // The turn the model does not tell: the spread of the fitted turns beyond what they would show without one.
    Eigen::Vector3d excess = Eigen::Vector3d::Zero();
    const std::vector<PlacementTurn> turns = PlacementTurns(*calibration, stats, observations, anchors);
    for (const PlacementTurn& t : turns) excess += t.rotation.cwiseAbs2() - t.predicted.diagonal();
    if (!turns.empty()) stats.turn_u_rad = (excess / static_cast<double>(turns.size())).cwiseMax(0.0).cwiseSqrt();
    for (size_t i = 0; i < predicted_sq.size(); ++i) {
      for (int c = 0; c < 3; ++c) predicted_sq[i] += std::pow(stats.turn_u_rad[c], 2) * arms[i].cross(Eigen::Vector3d::Unit(c)).squaredNorm();
    }
  }
  static_cast<ResidualSummary&>(stats) = Summarize(stats.residuals);
  double sum = 0;
  for (double v : predicted_sq) sum += v;
  if (!predicted_sq.empty()) stats.predicted_rms_mm = std::sqrt(sum / static_cast<double>(predicted_sq.size()));
  return stats;
}

double UndeterminedRms(const Calibration& calibration, const std::vector<Observation>& observations,
                       const std::vector<Eigen::Vector3d>& anchors, StitchedFrame frame) {
  const std::optional<Calibration> spread = UndeterminedSpread(calibration);
  if (!spread || observations.empty()) return 0.0;
  // The spread is propagated in the frames the calibration itself turns the measurements in.
  const std::vector<FirstTileCompensation> frames = FirstTileFrames(*spread, anchors, ModelFrame(calibration, anchors, frame));
  double sum = 0;
  for (const Observation& o : observations) {
    Eigen::MatrixXd j;
    Predicted(*spread, frames, o, &j);
    sum += (j * spread->covariance * j.transpose()).trace();
  }
  return std::sqrt(sum / static_cast<double>(observations.size()));
}

std::vector<PlacementTurn> PlacementTurns(const Calibration& calibration, const ValidationStats& validation,
                                          const std::vector<Observation>& observations,
                                          const std::vector<Eigen::Vector3d>& anchors) {
  std::map<int, PlacementTurn> by_group;
  for (size_t i = 0; i < observations.size(); ++i) {
    PlacementTurn& t = by_group[observations[i].group];
    t.group = observations[i].group;
    t.observations.push_back(i);
    t.arms.push_back(observations[i].measured - anchors.at(static_cast<size_t>(observations[i].group)));
  }
  const double sigma2 = calibration.sigma_mm * calibration.sigma_mm;
  const bool covariance = calibration.covariance.size() > 0 && validation.jacobians.size() == observations.size();
  std::vector<PlacementTurn> out;
  for (auto& [group, t] : by_group) {
    if (t.observations.size() < 3) continue;
    std::vector<Eigen::Vector3d> residuals;
    for (size_t i : t.observations) residuals.push_back(validation.residuals[i]);
    const TurnFit fit = FitTurn(residuals, t.arms);
    t.rotation = fit.rotation;
    t.solve = fit.solve;
    t.noise = sigma2 * fit.solve * fit.solve.transpose();
    t.predicted = t.noise;
    if (covariance) {
      Eigen::MatrixXd j(3 * static_cast<Eigen::Index>(t.observations.size()), calibration.covariance.cols());
      for (size_t k = 0; k < t.observations.size(); ++k) j.middleRows(3 * static_cast<Eigen::Index>(k), 3) = validation.jacobians[t.observations[k]];
      t.sensitivity = fit.solve * j;
      t.predicted += t.sensitivity * calibration.covariance * t.sensitivity.transpose();
    }
    out.push_back(std::move(t));
  }
  return out;
}

namespace {

// The observations of each group, in their order.
std::map<int, std::vector<const Observation*>> ByGroup(const std::vector<Observation>& observations) {
  std::map<int, std::vector<const Observation*>> out;
  for (const Observation& o : observations) out[o.group].push_back(&o);
  return out;
}

double Variance(const Calibration* calibration, const Eigen::MatrixXd& j) {
  if (calibration == nullptr || calibration->covariance.size() == 0) return 0.0;
  return (j * calibration->covariance * j.transpose()).trace();
}

}  // namespace

FrameFreeStats RigidValidation(const Calibration* calibration, const std::vector<Observation>& observations) {
  FrameFreeStats stats;
  double sum_sq = 0, predicted_sq = 0;
  const double sigma = calibration ? calibration->sigma_mm : 0.0;
  for (const auto& [group, members] : ByGroup(observations)) {
    const Eigen::Index n = static_cast<Eigen::Index>(members.size());
    if (n < 3) continue;
    Eigen::Matrix3Xd p(3, n), s(3, n);
    std::vector<Eigen::MatrixXd> j(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      p.col(i) = Compensated(calibration, members[static_cast<size_t>(i)]->command, &j[static_cast<size_t>(i)]);
      s.col(i) = members[static_cast<size_t>(i)]->measured;
    }
    const Eigen::Matrix4d t = Eigen::umeyama(p, s, false);
    const Eigen::Matrix3Xd r = (t.topLeftCorner<3, 3>() * p).colwise() + t.topRightCorner<3, 1>() - s;
    for (Eigen::Index i = 0; i < n; ++i) {
      sum_sq += r.col(i).squaredNorm();
      stats.max_mm = std::max(stats.max_mm, r.col(i).norm());
    }
    stats.count += static_cast<int>(n);
    if (calibration == nullptr) continue;
    // What a rigid motion of the measurement cannot take: the complement of translations and small rotations
    // about its centroid, applied to the model's uncertainty; the noise keeps 3n - 6 of its 3n degrees of freedom.
    const Eigen::Vector3d centroid = p.rowwise().mean();
    Eigen::MatrixXd rigid = Eigen::MatrixXd::Zero(3 * n, 6);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d d = p.col(i) - centroid;
      rigid.block<3, 3>(3 * i, 0).setIdentity();
      rigid.block<3, 3>(3 * i, 3) = -Skew(d);  // a small rotation w about the centroid moves d by w x d
    }
    const auto qr = Decompose<Eigen::HouseholderQR<Eigen::MatrixXd>>(rigid, "validation: the rigid motions of a placement");
    const Eigen::MatrixXd q = Eigen::MatrixXd(qr.householderQ()).leftCols(6);
    if (calibration->covariance.size() > 0) {
      Eigen::MatrixXd stacked(3 * n, calibration->covariance.cols());
      for (Eigen::Index i = 0; i < n; ++i) stacked.middleRows(3 * i, 3) = j[static_cast<size_t>(i)];
      predicted_sq += Variance(calibration, stacked - q * (q.transpose() * stacked));
    }
    predicted_sq += sigma * sigma * static_cast<double>(3 * n - 6);
  }
  if (stats.count > 0) {
    stats.rms_mm = std::sqrt(sum_sq / stats.count);
    stats.predicted_rms_mm = std::sqrt(predicted_sq / stats.count);
  }
  return stats;
}

FrameFreeStats PairDistanceValidation(const Calibration* calibration, const std::vector<Observation>& observations) {
  FrameFreeStats stats;
  double sum_sq = 0, predicted_sq = 0;
  const double sigma = calibration ? calibration->sigma_mm : 0.0;
  for (const auto& [group, members] : ByGroup(observations)) {
    std::vector<Eigen::Vector3d> p;
    std::vector<Eigen::MatrixXd> j(members.size());
    for (size_t i = 0; i < members.size(); ++i) p.push_back(Compensated(calibration, members[i]->command, &j[i]));
    for (size_t a = 0; a < members.size(); ++a) {
      for (size_t b = a + 1; b < members.size(); ++b) {
        const Eigen::Vector3d d = p[a] - p[b];
        const double e = d.norm() - (members[a]->measured - members[b]->measured).norm();
        sum_sq += e * e;
        stats.max_mm = std::max(stats.max_mm, std::abs(e));
        ++stats.count;
        if (calibration == nullptr) continue;
        const Eigen::RowVector3d u = d.normalized().transpose();
        predicted_sq += Variance(calibration, u * (j[a] - j[b])) + 2 * sigma * sigma;
      }
    }
  }
  if (stats.count > 0) {
    stats.rms_mm = std::sqrt(sum_sq / stats.count);
    stats.predicted_rms_mm = std::sqrt(predicted_sq / stats.count);
  }
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
