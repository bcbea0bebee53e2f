#include "stage/held_out_turn_test.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>

#include "stage/discrepancy_scoring.h"

namespace fvm::stage {
namespace {

// What the coefficients the identification data could not determine (fixed, e.g. pitch and roll on flat bars) add
// to the covariance of the held-out yaws: their true values still act on placements the identification did not
// cover. Without a truth to go by, each gets the mean square of the determined coefficients of its kind (rotation,
// translation, squareness) and power as its variance: empirical Bayes, as large as its determined kin. Their yaw
// sensitivities are those PlacementTurns gives for the calibration with them set free, in the same frame.
Eigen::MatrixXd UndeterminedYawCovariance(const Calibration& calibration, const MeasurementSet& validate, StitchedFrame frame,
                                          Eigen::Index placements) {
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(placements, placements);
  const ParameterLayout& layout = calibration.layout;
  std::map<std::pair<int, int>, std::pair<double, int>> kin;  // (kind, power) -> (sum of squares, count)
  std::vector<const ParameterLayout::Coefficient*> fixed;
  for (const ParameterLayout::Coefficient& c : layout.coefficients()) {
    const std::pair<int, int> key{static_cast<int>(GetErrorTerm(c.term).kind), c.power};
    const int slot = layout.FreeIndexOf(c.name);
    if (slot >= 0) {
      kin[key].first += std::pow(calibration.values[static_cast<size_t>(slot)], 2);
      ++kin[key].second;
    } else if (c.state == ParameterLayout::State::kFixed) {
      fixed.push_back(&c);
    }
  }
  if (fixed.empty()) return covariance;
  Calibration freed = calibration;
  for (const ParameterLayout::Coefficient* c : fixed) freed.layout.Free(c->name);
  freed.values = ValuesByName(layout, calibration.values, freed.layout);
  for (const ParameterLayout::Coefficient* c : fixed) freed.values[static_cast<size_t>(freed.layout.FreeIndexOf(c->name))] = c->value;
  freed.covariance = Eigen::MatrixXd::Zero(freed.layout.NumFree(), freed.layout.NumFree());  // asks for the sensitivities
  const ValidationStats v = Validate(&freed, validate.observations, validate.anchors, frame);
  const std::vector<PlacementTurn> turns = PlacementTurns(freed, v, validate.observations, validate.anchors);
  if (static_cast<Eigen::Index>(turns.size()) != placements) return covariance;
  for (const ParameterLayout::Coefficient* c : fixed) {
    const auto it = kin.find({static_cast<int>(GetErrorTerm(c->term).kind), c->power});
    if (it == kin.end()) continue;
    Eigen::VectorXd yaw(placements);
    for (Eigen::Index g = 0; g < placements; ++g) yaw[g] = turns[static_cast<size_t>(g)].sensitivity(2, freed.layout.FreeIndexOf(c->name));
    covariance += it->second.first / it->second.second * yaw * yaw.transpose();
  }
  return covariance;
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
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(a.transpose() * a);
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
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(covariance);
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

}  // namespace fvm::stage
