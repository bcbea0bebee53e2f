#include "stage/held_out_turn_test.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <string>

#include "core/dense_decomposition.h"
#include "stage/discrepancy_scoring.h"
#include "stage/undetermined_spread.h"

namespace fvm::stage {
namespace {

// What the coefficients identification fixed as undetermined (e.g. pitch and roll on flat bars) add to the
// covariance of the held-out yaws: their true values still act on placements the identification did not cover,
// less what the free coefficients took up of them (stage/undetermined_spread.h, the same spread the validation's
// prediction carries). Their yaw sensitivities are those PlacementTurns gives for the calibration with them set free,
// in the same frame.
Eigen::MatrixXd UndeterminedYawCovariance(const Calibration& calibration, const MeasurementSet& validate, StitchedFrame frame,
                                          Eigen::Index placements) {
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(placements, placements);
  const std::optional<Calibration> spread = UndeterminedSpread(calibration);
  if (!spread) return covariance;
  const ValidationStats v = Validate(&*spread, validate.observations, validate.anchors, frame);
  const std::vector<PlacementTurn> turns = PlacementTurns(*spread, v, validate.observations, validate.anchors);
  if (static_cast<Eigen::Index>(turns.size()) != placements) return covariance;
  Eigen::MatrixXd yaw(placements, spread->covariance.cols());
  for (Eigen::Index g = 0; g < placements; ++g) yaw.row(g) = turns[static_cast<size_t>(g)].sensitivity.row(2);
  return yaw * spread->covariance * yaw.transpose();
}

}  // namespace

TurnTest TestHeldOutTurns(const Calibration& calibration, const MeasurementSet& validate, StitchedFrame frame,
                          const std::optional<DriftCorrection>& drift, double alpha_each) {
  TurnTest t;
  const ValidationStats v = Validate(&calibration, validate.observations, validate.anchors, frame);
  t.turns = PlacementTurns(calibration, v, validate.observations, validate.anchors);
  t.residuals_after = v.residuals;
  for (const PlacementTurn& turn : t.turns) {
    for (size_t k = 0; k < turn.observations.size(); ++k) {
      t.residuals_after[turn.observations[k]] -= TurnDisplacement(turn.rotation, turn.arms[k]);
    }
  }
  // The test looks at the yaws, which an in-plane placement always shows (tilts about the first tile are also what
  // a model that cannot determine pitch and roll gets wrong), jointly: an error of the model turns every
  // placement alike, so their yaws are correlated through the calibration's covariance.
  const Eigen::Index n = static_cast<Eigen::Index>(t.turns.size());
  if (n == 0) return t;
  Eigen::VectorXd yaw(n);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(n, n);
  const bool model = calibration.covariance.size() > 0;
  // With a drift: the yaw's sensitivity to its three rates joins that to the coefficients, under their joint
  // covariance.
  Eigen::MatrixXd joint = calibration.covariance;
  Eigen::MatrixXd drift_yaw = Eigen::MatrixXd::Zero(n, drift ? 3 : 0);
  if (drift && model && !validate.t_s.empty()) {
    Eigen::MatrixXd a(drift->model_columns.rows(), drift->model_columns.cols() + 3);
    a << drift->model_columns, drift->drift_columns;
    const auto cod = Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(
        a.transpose() * a, "the held-out turns: the normal equations of the model and its drift");
    joint = calibration.sigma_mm * calibration.sigma_mm * cod.pseudoInverse();
    for (Eigen::Index g = 0; g < n; ++g) {
      const PlacementTurn& turn = t.turns[static_cast<size_t>(g)];
      for (size_t i = 0; i < turn.observations.size(); ++i) {
        const double shift = -DriftShape(validate.t_s[turn.observations[i]], drift->tau_s);
        drift_yaw.row(g) += shift * turn.solve.block<1, 3>(2, 3 * static_cast<Eigen::Index>(i));
      }
    }
  }
  const auto yaw_sensitivity = [&](Eigen::Index g) {
    const PlacementTurn& turn = t.turns[static_cast<size_t>(g)];
    Eigen::RowVectorXd row(turn.sensitivity.cols() + drift_yaw.cols());
    row << turn.sensitivity.row(2), drift_yaw.row(g);
    return row;
  };
  for (Eigen::Index g = 0; g < n; ++g) {
    const PlacementTurn& a = t.turns[static_cast<size_t>(g)];
    yaw[g] = a.rotation.z();
    covariance(g, g) = a.noise(2, 2);
    for (Eigen::Index h = 0; h < n && model && a.sensitivity.size() > 0; ++h) {
      covariance(g, h) += yaw_sensitivity(g).dot(joint * yaw_sensitivity(h).transpose());
    }
  }
  if (model) covariance += UndeterminedYawCovariance(calibration, validate, frame, n);
  const auto ldlt = Decompose<Eigen::LDLT<Eigen::MatrixXd>>(covariance, "the held-out turns: the covariance of the yaws");
  if (ldlt.info() != Eigen::Success || !(covariance.diagonal().minCoeff() > 0)) return t;
  const double chi2 = yaw.dot(ldlt.solve(yaw));
  const int dof = static_cast<int>(n);
  const double m = 3.0 * static_cast<double>(v.residuals.size());
  double rss_before = 0, rss_after = 0;
  for (size_t i = 0; i < v.residuals.size(); ++i) {
    rss_before += v.residuals[i].squaredNorm();
    rss_after += t.residuals_after[i].squaredNorm();
  }
  t.score.extra_parameters = dof;
  t.score.f_statistic = chi2 / dof;
  t.score.p_value = boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<double>(dof), chi2));
  t.score.delta_bic = m * std::log(rss_after / rss_before) + dof * std::log(m);
  t.score.significant = t.score.p_value < alpha_each && t.score.delta_bic < 0;
  return t;
}

DiagnosisStep FrameRotationStep(const TurnTest& turn, const ParameterLayout& layout, const ResidualSummary& fit,
                                const ResidualSummary& validation, const std::vector<std::string>& groups,
                                std::vector<PlacementTurnFinding>* turns) {
  DiagnosisStep s;
  s.effect = "frame_rotation";
  s.component.assign(1, 'z');  // (= "z" trips a false -Wrestrict of GCC 12 here)
  double yaw_sq = 0, u_sq = 0;
  for (const PlacementTurn& t : turn.turns) {
    const Eigen::Vector3d u = t.predicted.diagonal().cwiseMax(0.0).cwiseSqrt();
    const std::string name = static_cast<size_t>(t.group) < groups.size() ? groups[static_cast<size_t>(t.group)]
                                                                          : std::to_string(t.group);
    turns->push_back({name, t.rotation, u});
    yaw_sq += t.rotation.z() * t.rotation.z();
    u_sq += u.z() * u.z();
  }
  // The rms yaw over the placements less what their own noise adds, and the standard uncertainty of that rms.
  const double count = static_cast<double>(std::max<size_t>(1, turn.turns.size()));
  s.size = std::sqrt(std::max(0.0, yaw_sq - u_sq) / count) * 1e6;
  s.size_u = std::sqrt(u_sq / count / count) * 1e6;
  s.size_unit = "urad";
  s.before = s.after = fit;
  s.validation_before = validation;
  s.validation_after = Summarize(turn.residuals_after);
  s.candidates = {turn.score};
  const std::vector<std::string> turn_terms = TurnCoefficients(layout);
  s.explanation = fmt::format(
      "The held-out placements' residuals grow perpendicular to, and in proportion to, their distance from the "
      "first tile: each stitched measurement is turned about its first tile ({:.1f} +- {:.1f} urad rms yaw over {} "
      "placements). The instrument registers tiles by translation, so a mosaic keeps the orientation the stage "
      "had at its first tile; identification placements that share a start share that turn and the model's "
      "constant terms absorb it, so only placements that start elsewhere show it. {}",
      s.size, s.size_u, turn.turns.size(),
      turn_terms.empty()
          ? "This model has no rotation terms that vary over the stage: a model of order 1 or more (27, 42) can "
            "tell the turn at each first tile."
          : fmt::format("fvm calibrate --stitched-frame rotated (the default) turns each placement by the model's own "
                        "{}.",
                        fmt::join(turn_terms, ", ")));
  return s;
}

}  // namespace fvm::stage
