#include "core/statistics.h"
#include "stage/discrepancy.h"

#include <fmt/core.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>

#include "stage/stitched_frame.h"
#include "stage/validation.h"

namespace fvm::stage {
namespace {

Eigen::VectorXd Stack(const std::vector<Eigen::Vector3d>& v) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
  return out;
}

// d(residual)/d(coefficients named) for every observation, columns scaled to unit norm (the F-test and the
// rank decisions do not depend on units).
Eigen::MatrixXd CoefficientColumns(const ParameterLayout& layout, const std::vector<double>& values,
                                   const std::vector<std::string>& names, const MeasurementSet& set, bool anchored) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()),
                                                  static_cast<Eigen::Index>(names.size()));
  std::vector<Eigen::MatrixXd> anchor_jacobians;
  for (const Eigen::Vector3d& a : set.anchors) anchor_jacobians.push_back(ForwardJacobian(layout, values.data(), a));
  for (size_t i = 0; i < set.observations.size(); ++i) {
    Eigen::MatrixXd j = ForwardJacobian(layout, values.data(), set.observations[i].command);
    if (anchored) j -= anchor_jacobians[static_cast<size_t>(set.observations[i].group)];
    for (size_t c = 0; c < names.size(); ++c) {
      columns.block<3, 1>(3 * static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) = j.col(layout.FreeIndexOf(names[c]));
    }
  }
  return columns;
}

std::vector<double> ValuesByName(const ParameterLayout& from, const std::vector<double>& values, const ParameterLayout& to) {
  std::vector<double> out;
  for (const std::string& name : to.FreeNames()) {
    const int slot = from.FreeIndexOf(name);
    out.push_back(slot >= 0 ? values[static_cast<size_t>(slot)] : 0.0);
  }
  return out;
}

struct LinearScore {
  double rss_base = 0, rss = 0;
  double rows = 0;     // equations it was scored on
  double own = 0;      // the least share of a column's pattern (norm) that the base model cannot take
  int extra = 0;       // rank the candidate adds
  int rank = 0;        // rank of base + candidate
  Eigen::VectorXd effect;      // least-squares values of the candidate's columns (in the columns' units)
  Eigen::VectorXd effect_u;    // their standard uncertainties
};

// Extra sum of squares of the candidate columns over the base model, on the linearised problem.
//
// Only the part of a candidate that the base model leaves above 1 % of its norm counts as new. Below that, its
// estimate would rest on what the model does not describe rather than on the effect: a scale about a shared start
// is the model's linear terms xTx1 and yTy1 but for the noise, the bar's pitch errors and the stage's own
// non-polynomial error in the stitched coordinates it is built from (about 1e-4 of them), and fitted to that
// remainder it comes out at 1e6 ppm.
LinearScore ScoreColumns(const Eigen::VectorXd& r0, const Eigen::MatrixXd& base, const Eigen::MatrixXd& extra) {
  constexpr double kNewDirection = 1e-2;
  LinearScore s;
  s.rows = static_cast<double>(r0.size());
  Eigen::MatrixXd all(base.rows(), base.cols() + extra.cols());
  all << base, extra;
  Eigen::VectorXd norms = all.colwise().norm();
  for (Eigen::Index c = 0; c < all.cols(); ++c) {
    if (norms[c] > 0) all.col(c) /= norms[c];
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> base_qr(all.leftCols(base.cols()));
  base_qr.setThreshold(1e-9);
  const int base_rank = static_cast<int>(base_qr.rank());
  const Eigen::MatrixXd q_base = Eigen::MatrixXd(base_qr.householderQ()).leftCols(base_rank);
  const Eigen::VectorXd r_base = r0 - q_base * (q_base.transpose() * r0);
  s.rss_base = r_base.squaredNorm();
  Eigen::MatrixXd unique = all.rightCols(extra.cols()) - q_base * (q_base.transpose() * all.rightCols(extra.cols()));
  s.own = 1.0;
  for (Eigen::Index c = 0; c < unique.cols(); ++c) {
    if (unique.col(c).norm() < kNewDirection) unique.col(c).setZero();
    else s.own = std::min(s.own, unique.col(c).norm());
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> extra_qr(unique);
  extra_qr.setThreshold(kNewDirection);
  s.extra = static_cast<int>(extra_qr.rank());
  s.rank = base_rank + s.extra;
  const Eigen::MatrixXd q_extra = Eigen::MatrixXd(extra_qr.householderQ()).leftCols(s.extra);
  s.rss = std::max(0.0, s.rss_base - (q_extra.transpose() * r_base).squaredNorm());
  // Effect estimates: minimum-norm least squares on the whole system, then undo the column scaling.
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(all);
  const Eigen::VectorXd solution = cod.solve(-r0);
  const double dof = std::max(1.0, static_cast<double>(all.rows() - s.rank));
  const double sigma2 = s.rss / dof;
  const Eigen::MatrixXd normal_inverse = cod.pseudoInverse() * cod.pseudoInverse().transpose();
  s.effect.resize(extra.cols());
  s.effect_u.resize(extra.cols());
  for (Eigen::Index c = 0; c < extra.cols(); ++c) {
    const Eigen::Index k = base.cols() + c;
    const double n = norms[k] > 0 ? norms[k] : 1.0;
    s.effect[c] = solution[k] / n;
    s.effect_u[c] = std::sqrt(std::max(0.0, sigma2 * normal_inverse(k, k))) / n;
  }
  return s;
}

// ScoreColumns without the equations of some observations: centres flagged as blunders, whose 80 um would otherwise
// swamp the F-test of a 5 um effect (and pull its estimate).
LinearScore ScoreColumnsWithout(const std::vector<int>& left_out, const Eigen::VectorXd& r0, const Eigen::MatrixXd& base,
                                const Eigen::MatrixXd& extra) {
  if (left_out.empty()) return ScoreColumns(r0, base, extra);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < r0.size(); ++i) {
    if (std::find(left_out.begin(), left_out.end(), static_cast<int>(i / 3)) == left_out.end()) rows.push_back(i);
  }
  return ScoreColumns(r0(rows), base(rows, Eigen::all), extra(rows, Eigen::all));
}

struct Candidate {
  EffectScore score;
  LinearScore linear;
  std::vector<std::string> coefficient_names;  // higher_order, z_coupling
  std::vector<int> flagged;                    // outliers: observation indices
  double tau_s = 0.0;                          // thermal_drift: 0 linear, else the warm-up's time constant
};

// How far a drift of initial rate 1 has gone after t: t itself (linear), or tau (1 - exp(-t/tau)), the warm-up
// rho(t) = A + B (1 - exp(-t/tau)) of [Pérez thesis] eqs. 5.1-5.2 with B = rate * tau (A is the model's constant).
double DriftShape(double t, double tau) { return tau > 0 ? tau * (1.0 - std::exp(-t / tau)) : t; }

void Test(Candidate& c, double alpha_each) {
  const LinearScore& l = c.linear;
  const double m = l.rows;
  c.score.extra_parameters = l.extra;
  if (l.extra <= 0 || l.rss <= 0 || m - l.rank <= 0) return;
  const double d1 = l.extra, d2 = m - l.rank;
  c.score.f_statistic = ((l.rss_base - l.rss) / d1) / (l.rss / d2);
  const boost::math::fisher_f_distribution<double> f(d1, d2);
  c.score.p_value = c.score.f_statistic > 0 ? boost::math::cdf(boost::math::complement(f, c.score.f_statistic)) : 1.0;
  c.score.delta_bic = m * std::log(l.rss / l.rss_base) + d1 * std::log(m);
  c.score.significant = c.score.p_value < alpha_each && c.score.delta_bic < 0;
}

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const Eigen::Map<const Eigen::VectorXd> x(a.data(), static_cast<Eigen::Index>(a.size()));
  const Eigen::Map<const Eigen::VectorXd> y(b.data(), static_cast<Eigen::Index>(b.size()));
  const Eigen::VectorXd dx = x.array() - x.mean(), dy = y.array() - y.mean();
  const double d = dx.norm() * dy.norm();
  return d > 0 ? dx.dot(dy) / d : 0.0;
}

// What a metrologist would look at first: residuals against position, height, time, calotte index; per-placement
// offsets; the largest standardised residual.
std::vector<std::string> Findings(const std::vector<Eigen::Vector3d>& residuals, const MeasurementSet& set, double sigma) {
  std::vector<std::pair<double, std::string>> found;
  std::map<std::string, std::vector<double>> covariates;
  std::map<int, int> index_in_group;
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const Observation& o = set.observations[i];
    covariates["x"].push_back(o.command.x());
    covariates["y"].push_back(o.command.y());
    covariates["height z"].push_back(o.command.z());
    covariates["calotte index"].push_back(index_in_group[o.group]++);
    if (!set.t_s.empty()) covariates["time"].push_back(set.t_s[i]);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<double> component;
    for (const Eigen::Vector3d& r : residuals) component.push_back(r[c]);
    for (const auto& [name, values] : covariates) {
      const double rho = Correlation(component, values);
      if (std::abs(rho) > 0.3) {
        found.emplace_back(std::abs(rho), fmt::format("residual {} follows {} (correlation {:+.2f})", "xyz"[c], name, rho));
      }
    }
  }
  std::map<int, std::pair<Eigen::Vector3d, int>> per_group;
  for (size_t i = 0; i < residuals.size(); ++i) {
    auto& [sum, n] = per_group[set.observations[i].group];
    if (n == 0) sum.setZero();
    sum += residuals[i];
    ++n;
  }
  for (const auto& [group, sum_n] : per_group) {
    const Eigen::Vector3d mean = sum_n.first / sum_n.second;
    const double z = mean.norm() / (sigma / std::sqrt(sum_n.second));
    if (z > 4) {
      const std::string name = static_cast<size_t>(group) < set.groups.size() ? set.groups[static_cast<size_t>(group)] : std::to_string(group);
      found.emplace_back(z / 10, fmt::format("placement {} sits {:.1f} um off on average ({:.1f} sigma)", name, mean.norm() * 1e3, z));
    }
  }
  size_t worst = 0;
  for (size_t i = 1; i < residuals.size(); ++i) {
    if (residuals[i].norm() > residuals[worst].norm()) worst = i;
  }
  if (!residuals.empty() && residuals[worst].norm() > 5 * sigma * std::sqrt(3.0)) {
    found.emplace_back(1.0, fmt::format("largest residual {:.1f} um at {} ({:.1f} sigma)", residuals[worst].norm() * 1e3,
                                        set.labels.empty() ? std::to_string(worst) : set.labels[worst],
                                        residuals[worst].norm() / sigma));
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::string> out;
  for (size_t i = 0; i < found.size() && i < 5; ++i) out.push_back(found[i].second);
  if (out.empty()) out.push_back("no structure: residuals look like noise against position, height, time and index");
  return out;
}

// The next power of a term's polynomial; its existing coefficients keep their states (dropped stay dropped,
// fixed stay fixed).
void RaiseOrder(ParameterLayout& layout, const std::string& term) {
  const int index = *FindErrorTerm(term);
  const TermSpec spec = layout.term(index);
  std::vector<ParameterLayout::Coefficient> kept;
  for (const ParameterLayout::Coefficient& c : layout.coefficients()) {
    if (c.term == index) kept.push_back(c);
  }
  layout.SetTerm(term, spec.basis, spec.order + 1);
  for (int p = 0; p <= spec.order; ++p) {
    const std::string name = term + std::to_string(p);
    const auto it = std::find_if(kept.begin(), kept.end(), [&](const auto& c) { return c.name == name; });
    if (it == kept.end()) {
      layout.Drop(name);
    } else if (it->state == ParameterLayout::State::kFixed) {
      layout.Fix(name, it->value);
    }
  }
}

// Pitch and roll of X and Y (order 0) where the layout lacks them.
void AddPitchAndRoll(ParameterLayout& layout) {
  for (const char* term : {"xRx", "xRy", "yRx", "yRy"}) {
    if (!layout.term(*FindErrorTerm(term)).present) layout.SetTerm(term, Basis::kPower, 0);
  }
}

// A measurement set with each observation changed by `change` (observation, index).
MeasurementSet Changed(const MeasurementSet& set, const std::function<void(Observation&, size_t)>& change) {
  MeasurementSet out = set;
  for (size_t i = 0; i < out.observations.size(); ++i) change(out.observations[i], i);
  return out;
}

// frame_rotation on the held-out placements: each one's turn about its first tile, fitted to the calibration's
// residuals (PlacementTurns) and tested against what the calibration's covariance and the noise predict for
// it when there is no turn: chi^2 of the yaws; the step then takes each placement's whole turn out.
struct TurnTest {
  EffectScore score{"frame_rotation", "", 0, 0.0, 1.0, 0.0, false};
  std::vector<PlacementTurn> turns;
  std::vector<Eigen::Vector3d> residuals_after;  // with each placement's turn taken out
};

// A drift the data were corrected by. Its rates were estimated together with the model's coefficients, which along
// bars measured in order trade off against them: the turn test takes their joint covariance, from the equations
// of both on the identification data.
struct DriftCorrection {
  Eigen::MatrixXd model_columns, drift_columns;  // d(identification residual) / d(free coefficients), / d(rates)
  double tau_s = 0.0;
};

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

// What an accepted step added, with the values it was estimated at: enough to rebuild the problem with or without
// it (the backward check).
struct Applied {
  DiagnosisStep step;
  std::vector<std::string> coefficient_names;            // higher_order, z_coupling
  Eigen::Vector3d drift_mm_per_s = Eigen::Vector3d::Zero();  // thermal_drift: its initial rate
  double tau_s = 0.0;                                    // thermal_drift: 0 linear, else a warm-up's time constant
  double scale = 0.0;                                    // scale
  std::vector<int> flagged;                              // outliers: indices into the original identification set
  int extra = 0;                                         // parameters it added
};

// The problem a step fits: the base model and data with every applied effect.
struct Problem {
  ParameterLayout layout;
  MeasurementSet identify, validate;
  Anchor anchor = Anchor::kNone;
  std::vector<int> original;  // index of each identification observation in the original set
};

MeasurementSet Undrifted(const MeasurementSet& set, const Eigen::Vector3d& v, double tau) {
  if (set.t_s.empty()) return set;
  return Changed(set, [&](Observation& o, size_t i) { o.command -= v * DriftShape(set.t_s[i], tau); });
}

MeasurementSet Unscaled(const MeasurementSet& set, double kappa) {
  if (set.anchors.empty()) return set;
  return Changed(set, [&](Observation& o, size_t) {
    const Eigen::Vector3d a = set.anchors[static_cast<size_t>(o.group)];
    o.measured.head<2>() = a.head<2>() + (o.measured - a).head<2>() / (1.0 + kappa);
  });
}

Problem Build(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate, Anchor anchor,
              const std::vector<Applied>& applied) {
  Problem p{layout, identify, validate, anchor, {}};
  std::vector<int> dropped;
  for (const Applied& a : applied) {
    const std::string& e = a.step.effect;
    if (e == "higher_order") RaiseOrder(p.layout, a.step.component);
    if (e == "z_coupling") AddPitchAndRoll(p.layout);
    if (e == "reference_anchor") p.anchor = Anchor::kFirstTile;
    if (e == "thermal_drift") {
      p.identify = Undrifted(p.identify, a.drift_mm_per_s, a.tau_s);
      p.validate = Undrifted(p.validate, a.drift_mm_per_s, a.tau_s);
    }
    if (e == "scale") p.identify = Unscaled(p.identify, a.scale), p.validate = Unscaled(p.validate, a.scale);
    if (e == "outliers") dropped.insert(dropped.end(), a.flagged.begin(), a.flagged.end());
  }
  // Outliers last: the indices refer to the original set, which the other effects change in place only.
  MeasurementSet kept = p.identify;
  kept.observations.clear();
  kept.t_s.clear();
  kept.labels.clear();
  for (size_t i = 0; i < p.identify.observations.size(); ++i) {
    if (std::find(dropped.begin(), dropped.end(), static_cast<int>(i)) != dropped.end()) continue;
    kept.observations.push_back(p.identify.observations[i]);
    if (!p.identify.t_s.empty()) kept.t_s.push_back(p.identify.t_s[i]);
    if (!p.identify.labels.empty()) kept.labels.push_back(p.identify.labels[i]);
    p.original.push_back(static_cast<int>(i));
  }
  p.identify = std::move(kept);
  return p;
}

bool IsApplied(const std::vector<Applied>& applied, const std::string& effect) {
  return std::any_of(applied.begin(), applied.end(), [&](const Applied& a) { return a.step.effect == effect; });
}

// Noise per coordinate that a few blunders cannot inflate: the median absolute residual (MAD) scaled to sigma.
double RobustSigma(const std::vector<Eigen::Vector3d>& residuals, double floor_mm) {
  std::vector<double> components;
  for (const Eigen::Vector3d& r : residuals) components.insert(components.end(), {std::abs(r.x()), std::abs(r.y()), std::abs(r.z())});
  if (components.empty()) return floor_mm;
  return std::max(1.4826 * HighMedian(std::move(components)), floor_mm);
}

// What sets observation i's residual apart from those of its neighbours in the same group (the calottes before and
// after it along the bar): r_i less their mean or, at the end of a bar, less the straight line through the two
// before it. Smooth along the bar, a missing effect leaves little of it; a blunder leaves nearly all. `noise` is
// its variance in units of one residual's (white noise): 1 + 1/2, or 1 + 4 + 1 for the straight line.
struct Spike {
  Eigen::Vector3d value;
  double noise;
};

Spike SpikeOf(const std::vector<Observation>& observations, const std::vector<Eigen::Vector3d>& residuals, size_t i) {
  const auto same = [&](long k) {
    return k >= 0 && k < static_cast<long>(observations.size()) && observations[static_cast<size_t>(k)].group == observations[i].group;
  };
  const long n = static_cast<long>(i);
  const auto r = [&](long k) { return residuals[static_cast<size_t>(k)]; };
  if (same(n - 1) && same(n + 1)) return {residuals[i] - (r(n - 1) + r(n + 1)) / 2, 1.5};
  if (same(n - 2) && same(n - 1)) return {residuals[i] - (2 * r(n - 1) - r(n - 2)), 6.0};
  if (same(n + 2) && same(n + 1)) return {residuals[i] - (2 * r(n + 1) - r(n + 2)), 6.0};
  if (same(n - 1)) return {residuals[i] - r(n - 1), 2.0};
  if (same(n + 1)) return {residuals[i] - r(n + 1), 2.0};
  return {residuals[i], 1.0};
}

// Centres whose error is improbable for Gaussian noise of the robust scale (Bonferroni [Dunn 1961] over the centres),
// and as improbable against their neighbours' (SpikeOf), found one at a time: the worst is taken out and the model
// refitted before the next is judged, so that a large blunder, which drags the fit towards itself, cannot make its
// good neighbours look bad. Indices into p.identify.
std::vector<int> FlagOutliers(const Problem& p, const IdentificationResult& fit, const IdentificationOptions& base_options,
                              double alpha) {
  std::vector<int> flagged;
  std::vector<int> index(p.identify.observations.size());
  std::iota(index.begin(), index.end(), 0);
  std::vector<Observation> kept = p.identify.observations;
  std::vector<Eigen::Vector3d> residuals = fit.residuals;
  const boost::math::chi_squared_distribution<double> chi2(3.0);
  const double limit = boost::math::quantile(boost::math::complement(chi2, alpha / static_cast<double>(kept.size())));
  const size_t most = kept.size() / 5;  // beyond a fifth of the centres, the "outliers" are the model's failure
  while (flagged.size() < most && !residuals.empty()) {
    const double sigma = RobustSigma(residuals, base_options.noise_floor_mm);
    // The worst centre beyond the limit that also stands out from its neighbours by as much (SpikeOf): a failed
    // sphere fit moves one centre, while an effect the model lacks moves its neighbours along the bar with it.
    std::vector<size_t> order(residuals.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return residuals[a].squaredNorm() > residuals[b].squaredNorm(); });
    size_t worst = residuals.size();
    for (const size_t i : order) {
      if (residuals[i].squaredNorm() / (sigma * sigma) <= limit) break;
      const Spike spike = SpikeOf(kept, residuals, i);
      if (spike.value.squaredNorm() / (spike.noise * sigma * sigma) > limit) {
        worst = i;
        break;
      }
    }
    if (worst == residuals.size()) break;
    flagged.push_back(index[worst]);
    kept.erase(kept.begin() + static_cast<long>(worst));
    index.erase(index.begin() + static_cast<long>(worst));
    IdentificationOptions o = base_options;
    o.anchor = p.anchor;
    o.anchors = p.identify.anchors;
    try {
      residuals = Identify(p.layout, kept, o).residuals;
    } catch (const std::invalid_argument&) {
      break;  // too few centres left for the model: stop flagging
    }
  }
  return flagged;
}

// d(residual)/d(drift rate) per coordinate: the centres move by rate * DriftShape(t).
Eigen::MatrixXd DriftColumns(const MeasurementSet& set, double tau) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()), 3);
  for (size_t i = 0; i < set.observations.size(); ++i) {
    for (int c = 0; c < 3; ++c) columns(3 * static_cast<Eigen::Index>(i) + c, c) = -DriftShape(set.t_s[i], tau);
  }
  return columns;
}

// d(residual)/d(scale): stitched xy distances from the first tile grow by scale * (s - a).
Eigen::MatrixXd ScaleColumn(const MeasurementSet& set) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()), 1);
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const Observation& o = set.observations[i];
    const Eigen::Vector3d a = set.anchors[static_cast<size_t>(o.group)];
    columns.block<2, 1>(3 * static_cast<Eigen::Index>(i), 0) = -(o.measured - a).head<2>();
  }
  return columns;
}

// Every candidate effect scored against the current fit (CoefficientColumns, ScoreColumns), but those already
// applied once (an anchor, a drift, a scale, outliers cannot be added twice). An applied drift or scale is a value
// the data were corrected by, not a model term: its directions join the base here, so that a later candidate is
// scored as if it could still move (a scale estimated alone takes part of a bend along x; with the bend it would not).
std::vector<Candidate> ScoreCandidates(const Problem& p, const IdentificationResult& fit, const ParameterLayout& base_layout,
                                       const std::vector<Applied>& applied, const IdentificationOptions& base_options,
                                       double alpha) {
  const MeasurementSet& identify = p.identify;
  const bool anchored = p.anchor == Anchor::kFirstTile;
  const Eigen::VectorXd r0 = Stack(fit.residuals);
  const ParameterLayout& fitted = fit.calibration.layout;
  Eigen::MatrixXd jb = CoefficientColumns(fitted, fit.calibration.values, fitted.FreeNames(), identify, anchored);
  for (const Applied& a : applied) {
    Eigen::MatrixXd free_again;
    if (a.step.effect == "thermal_drift" && !identify.t_s.empty()) free_again = DriftColumns(identify, a.tau_s);
    if (a.step.effect == "scale" && !identify.anchors.empty()) free_again = ScaleColumn(identify);
    if (free_again.cols() == 0) continue;
    jb.conservativeResize(Eigen::NoChange, jb.cols() + free_again.cols());
    jb.rightCols(free_again.cols()) = free_again;
  }
  const Eigen::Index rows = r0.size();
  std::vector<Candidate> candidates;
  // Blunders first: the other candidates are scored without them, so a large one cannot hide a small effect.
  std::vector<int> blunders;
  if (!IsApplied(applied, "outliers")) {
    Candidate c{{"outliers", ""}, {}, {}, FlagOutliers(p, fit, base_options, alpha)};
    if (!c.flagged.empty()) {
      Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 3 * static_cast<Eigen::Index>(c.flagged.size()));
      for (size_t k = 0; k < c.flagged.size(); ++k) {
        for (int j = 0; j < 3; ++j) columns(3 * c.flagged[k] + j, 3 * static_cast<Eigen::Index>(k) + j) = 1.0;
      }
      c.linear = ScoreColumns(r0, jb, columns);
      blunders = c.flagged;
      candidates.push_back(std::move(c));
    }
  }
  const auto score = [&](const Eigen::MatrixXd& columns) { return ScoreColumnsWithout(blunders, r0, jb, columns); };
  const auto coefficient_candidate = [&](const std::string& effect, const std::string& component,
                                         const std::function<void(ParameterLayout&)>& extend) {
    ParameterLayout extended = fitted;
    extend(extended);
    std::vector<std::string> added;
    for (const std::string& name : extended.FreeNames()) {
      if (fitted.FreeIndexOf(name) < 0) added.push_back(name);
    }
    if (added.empty()) return;
    const std::vector<double> values = ValuesByName(fitted, fit.calibration.values, extended);
    candidates.push_back({{effect, component}, score(CoefficientColumns(extended, values, added, identify, anchored)), added, {}});
  };
  for (int t = 0; t < kFirstSquarenessTerm; ++t) {
    const TermSpec& spec = p.layout.term(t);
    if (!spec.present || spec.order >= kMaxOrder || !base_layout.term(t).present) continue;
    const std::string term(GetErrorTerm(t).vdi);
    coefficient_candidate("higher_order", term, [&](ParameterLayout& l) { RaiseOrder(l, term); });
  }
  coefficient_candidate("z_coupling", "", AddPitchAndRoll);
  const auto column_candidate = [&](const std::string& effect, const std::string& component, const Eigen::MatrixXd& columns) {
    candidates.push_back(Candidate{{effect, component}, score(columns), {}, {}});
  };
  if (!anchored && identify.anchors.size() >= 2) {
    // Free offsets per placement (the first one is the reference): the most general anchor difference.
    Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 3 * static_cast<Eigen::Index>(identify.anchors.size() - 1));
    for (size_t i = 0; i < identify.observations.size(); ++i) {
      const int g = identify.observations[i].group;
      if (g == 0) continue;
      for (int c = 0; c < 3; ++c) columns(3 * static_cast<Eigen::Index>(i) + c, 3 * (g - 1) + c) = 1.0;
    }
    column_candidate("reference_anchor", "", columns);
  }
  if (!identify.t_s.empty() && !IsApplied(applied, "thermal_drift")) {
    column_candidate("thermal_drift", "", DriftColumns(identify, 0.0));
    const LinearScore& linear = candidates.back().linear;
    // A warm-up settling within the measurements: the time constant from a grid, counted as one more parameter. It
    // competes only when it beats the linear drift (its limit for a long time constant) by an F-test of its own.
    Candidate warm_up{{"thermal_drift", "warm-up"}, {}, {}, {}, 0.0};
    for (double tau_min : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0}) {
      const LinearScore l = score(DriftColumns(identify, tau_min * 60.0));
      if (warm_up.tau_s == 0.0 || l.rss < warm_up.linear.rss) warm_up.linear = l, warm_up.tau_s = tau_min * 60.0;
    }
    warm_up.linear.extra += 1;
    warm_up.linear.rank += 1;
    const double dof = warm_up.linear.rows - warm_up.linear.rank;
    if (dof > 0 && warm_up.linear.rss > 0 && linear.rss > warm_up.linear.rss) {
      const double f = (linear.rss - warm_up.linear.rss) / (warm_up.linear.rss / dof);
      const double p = boost::math::cdf(boost::math::complement(boost::math::fisher_f_distribution<double>(1.0, dof), f));
      if (p < alpha) candidates.push_back(std::move(warm_up));
    }
  }
  if (!identify.anchors.empty() && !IsApplied(applied, "scale")) {  // a scale about the first tile needs one
    column_candidate("scale", "xy", ScaleColumn(identify));
  }
  return candidates;
}

// A candidate as an effect to apply, with what can be said of it before the refit (coefficient effects get their
// size from the refit: FinishCoefficientEffect).
Applied MakeApplied(const Candidate& c, const Problem& p, const IdentificationResult& fit) {
  Applied a;
  a.step.effect = c.score.effect;
  a.step.component = c.score.component;
  a.coefficient_names = c.coefficient_names;
  a.extra = c.linear.extra;
  const LinearScore& l = c.linear;
  const std::string& effect = c.score.effect;
  if (effect == "reference_anchor") {
    double largest = 0;
    for (Eigen::Index k = 0; k < l.effect.size(); ++k) largest = std::max(largest, std::abs(l.effect[k]));
    a.step.size = largest * 1e3;
    a.step.size_u = (l.effect_u.size() ? l.effect_u.maxCoeff() : 0.0) * 1e3;
    a.step.size_unit = "um";
    a.step.explanation = fmt::format(
        "The placements did not start at one spot, and the instrument places the first tile of every stitched "
        "measurement by its encoders: each measurement carries the stage error of its own first tile (offsets up to "
        "{:.1f} +- {:.1f} um between placements). Referencing each measurement to its first tile (--anchor first-tile) "
        "removes them.", a.step.size, a.step.size_u);
  } else if (effect == "thermal_drift") {
    a.drift_mm_per_s = Eigen::Vector3d(l.effect[0], l.effect[1], l.effect[2]);
    a.tau_s = c.tau_s;
    Eigen::Index axis = 0;
    a.drift_mm_per_s.cwiseAbs().maxCoeff(&axis);
    const Eigen::Vector3d v = a.drift_mm_per_s * 6e4;  // um/min
    a.step.component = std::string(1, "xyz"[axis]) + (a.tau_s > 0 ? " warm-up" : "");
    a.step.size = v[axis];
    a.step.size_u = l.effect_u[axis] * 6e4;
    a.step.size_unit = "um/min";
    a.step.explanation =
        a.tau_s > 0
            ? fmt::format("The stitching-free centres drift with measurement time as a warm-up settles, rho(t) = A + B (1 - "
                          "exp(-t/tau)) ([Pérez thesis] eqs. 5.1-5.2): initial rate {:.2f} +- {:.2f} um/min along {} (all axes: {:.2f}, {:.2f}, "
                          "{:.2f} um/min), time constant about {:.1f} min, better than a drift linear in t.",
                          a.step.size, a.step.size_u, std::string(1, "xyz"[axis]), v.x(), v.y(), v.z(), a.tau_s / 60.0)
            : fmt::format("The stitching-free centres drift with measurement time: {:.2f} +- {:.2f} um/min along {} (all axes: "
                          "{:.2f}, {:.2f}, {:.2f} um/min), as a stage or column warming up would ([Pérez thesis] 5.7.1). Removing a "
                          "drift linear in t takes the time-correlated residuals away.",
                          a.step.size, a.step.size_u, a.step.component, v.x(), v.y(), v.z());
  } else if (effect == "scale") {
    a.scale = -l.effect[0];  // the column is -(s - a): its coefficient undoes the scale
    a.step.size = a.scale * 1e6;
    a.step.size_u = l.effect_u[0] * 1e6;
    a.step.size_unit = "ppm";
    a.step.explanation = fmt::format(
        "Stitched distances are scaled by {:.0f} +- {:.0f} ppm about the first tile: a lens (pixel size) or stitching scale "
        "error of the reference. The stage model cannot absorb a scale that restarts at every measurement's first tile.",
        a.step.size, a.step.size_u);
  } else if (effect == "outliers") {
    double largest = 0;
    for (int i : c.flagged) {
      a.flagged.push_back(p.original[static_cast<size_t>(i)]);
      const std::string name = p.identify.labels.empty() ? std::to_string(i) : p.identify.labels[static_cast<size_t>(i)];
      a.step.component += (a.step.component.empty() ? "" : ",") + name;
      largest = std::max(largest, fit.residuals[static_cast<size_t>(i)].norm());
    }
    a.step.size = largest * 1e3;
    a.step.size_u = fit.calibration.sigma_mm * std::sqrt(3.0) * 1e3;
    a.step.size_unit = "um";
    a.step.explanation = fmt::format(
        "{} centre(s) ({}) lie far outside the noise (largest {:.1f} um against {:.2f} um per coordinate): failed sphere "
        "fits, e.g. a burr or missing points in the calotte. Dropping them (or --loss cauchy) restores the fit.",
        c.flagged.size(), a.step.component, a.step.size, fit.calibration.sigma_mm * 1e3);
  }
  return a;
}

// higher_order and z_coupling: the largest added coefficient the refit could determine is the effect's size.
void FinishCoefficientEffect(Applied& a, const ParameterLayout& before, const Calibration& refit) {
  const Eigen::VectorXd u = refit.StandardUncertainty();
  std::string name;
  double largest = -1.0;
  for (const std::string& candidate : a.coefficient_names) {
    const int slot = refit.layout.FreeIndexOf(candidate);
    if (slot < 0) continue;
    const DisplayUnit unit = UnitOf(refit.layout.coefficients()[static_cast<size_t>(refit.layout.FindCoefficient(candidate))]);
    const double value = refit.values[static_cast<size_t>(slot)] * unit.per_si;
    if (std::abs(value) > largest) {
      largest = std::abs(value);
      name = candidate;
      a.step.size = value;
      a.step.size_u = u[slot] * unit.per_si;
      a.step.size_unit = unit.name;
    }
  }
  if (name.empty()) name = a.coefficient_names.front();
  if (a.step.effect == "z_coupling") a.step.component = name.substr(0, 3);
  a.step.explanation =
      a.step.effect == "higher_order"
          ? fmt::format("The {} error of the stage bends more than its order-{} polynomial can follow: adding {} ({:.2f} +- "
                        "{:.2f} {}) takes the residual structure along the axis away.",
                        a.step.component, before.term(*FindErrorTerm(a.step.component)).order, name, a.step.size,
                        a.step.size_u, a.step.size_unit)
          : fmt::format("The stage pitches and rolls ({} = {:.1f} +- {:.1f} urad): the artefact was measured at different "
                        "heights, and a rotation moves the lateral coordinates in proportion to the height, which the model "
                        "without pitch and roll cannot follow.",
                        name, a.step.size, a.step.size_u);
}

double ResidualSquares(const std::vector<Eigen::Vector3d>& residuals) {
  double s = 0;
  for (const Eigen::Vector3d& r : residuals) s += r.squaredNorm();
  return s;
}

}  // namespace

Diagnosis Diagnose(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate,
                   const DiagnosisOptions& options) {
  Diagnosis d;
  const IdentificationOptions& base_options = options.identification;
  const auto fit_of = [&](const Problem& p) {
    IdentificationOptions o = base_options;
    o.anchor = p.anchor;
    o.anchors = p.identify.anchors;
    return Identify(p.layout, p.identify.observations, o);
  };
  const auto held_out = [&](const Calibration& cal, const MeasurementSet& set) {
    if (set.observations.empty()) return ResidualSummary{};
    return static_cast<ResidualSummary>(Validate(&cal, set.observations, set.anchors, base_options.frame));
  };
  const auto build = [&](const std::vector<Applied>& applied) {
    return Build(layout, identify, validate, base_options.anchor, applied);
  };

  // A drift or a scale estimated again with every other applied effect in the model: it was estimated before the
  // later ones, and an outlier or a bend may have pulled it. True when the value changed.
  const auto reestimate = [&](std::vector<Applied>& list, size_t j, double alpha) {
    const std::string effect = list[j].step.effect;
    if (effect != "thermal_drift" && effect != "scale") return false;
    std::vector<Applied> without = list;
    without.erase(without.begin() + static_cast<long>(j));
    const Problem reduced = build(without);
    const IdentificationResult reduced_fit = fit_of(reduced);
    for (const Candidate& c : ScoreCandidates(reduced, reduced_fit, layout, without, base_options, alpha)) {
      if (c.score.effect != effect) continue;
      Applied fresh = MakeApplied(c, reduced, reduced_fit);
      fresh.step.before = list[j].step.before;
      fresh.step.after = list[j].step.after;
      fresh.step.validation_before = list[j].step.validation_before;
      fresh.step.validation_after = list[j].step.validation_after;
      fresh.step.candidates = list[j].step.candidates;
      list[j] = fresh;
      return true;
    }
    return false;
  };

  std::vector<Applied> applied;
  Problem problem = build(applied);
  IdentificationResult fit = fit_of(problem);
  d.residuals_before = fit.residuals;
  d.before = Summarize(fit.residuals);
  d.validation_before = held_out(fit.calibration, problem.validate);
  d.findings = Findings(fit.residuals, identify, RobustSigma(fit.residuals, base_options.noise_floor_mm));
  ResidualSummary validation = d.validation_before;
  const bool turns_testable = !validate.observations.empty() && !validate.anchors.empty();
  constexpr int kMostSteps = 6;
  int step = 1;
  for (; step <= kMostSteps; ++step) {
    // Alpha spending: step k may raise a false alarm with probability alpha / 2^k at most.
    const double alpha_step = options.alpha / std::pow(2.0, step);
    std::vector<Candidate> candidates = ScoreCandidates(problem, fit, layout, applied, base_options, alpha_step);
    const double alpha_each = alpha_step / static_cast<double>(std::max<size_t>(1, candidates.size() + (turns_testable ? 1 : 0)));
    for (Candidate& c : candidates) Test(c, alpha_each);
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      if (a.score.significant != b.score.significant) return a.score.significant;
      return a.score.delta_bic < b.score.delta_bic;
    });
    std::vector<EffectScore> scores;
    for (const Candidate& c : candidates) scores.push_back(c.score);
    if (step == 1) d.candidates = scores;
    bool accepted = false;
    for (const Candidate& c : candidates) {
      if (!c.score.significant) break;
      Applied a = MakeApplied(c, problem, fit);
      std::vector<Applied> with = applied;
      with.push_back(a);
      for (size_t j = 0; j + 1 < with.size(); ++j) reestimate(with, j, alpha_step);
      const Problem next = build(with);
      const IdentificationResult refit = fit_of(next);
      const ResidualSummary next_validation = held_out(refit.calibration, next.validate);
      // Held-out placements must not get worse (beyond their own scatter): otherwise the effect fitted noise.
      if (validation.count > 0 && next_validation.mean_mm > 1.05 * validation.mean_mm) {
        // Why it may fail: an effect whose pattern the model's terms nearly take is estimated from what little is
        // its own. A drift along bars measured in order is the usual case, and the design is the cure.
        const bool drift = c.score.effect == "thermal_drift";
        d.notes.push_back(fmt::format("step {}: {}{} fits the identification data better but makes the held-out placements "
                                      "worse ({:.2f} -> {:.2f} um; {:.0f} % of its pattern is its own, the rest the model "
                                      "can take){}; the next candidate was tried",
                                      step, c.score.effect, c.score.component.empty() ? "" : " " + c.score.component,
                                      validation.mean_mm * 1e3, next_validation.mean_mm * 1e3, 100 * c.linear.own,
                                      drift ? ". A drift grows along each bar as its calottes are measured in order, like "
                                              "anything else that grows along it; measuring every other placement "
                                              "backwards shows the drift at the shared start"
                                            : ""));
        continue;
      }
      if (!a.coefficient_names.empty()) FinishCoefficientEffect(a, problem.layout, refit.calibration);
      a.step.before = Summarize(fit.residuals);
      a.step.after = Summarize(refit.residuals);
      a.step.validation_before = validation;
      a.step.validation_after = next_validation;
      a.step.candidates = scores;
      for (const Candidate& other : candidates) {
        const double explained = c.linear.rss_base - c.linear.rss;
        if (&other == &c || other.linear.extra != c.linear.extra || !other.score.significant ||
            std::abs(other.linear.rss - c.linear.rss) > 1e-3 * explained) {
          continue;
        }
        a.step.alternatives.push_back(other.score.effect + (other.score.component.empty() ? "" : " " + other.score.component));
      }
      with.back() = a;
      applied = with;
      problem = next;
      fit = refit;
      validation = next_validation;
      accepted = true;
      break;
    }
    if (!accepted) break;
    // Backward check: an earlier effect the later ones made redundant no longer earns its parameters.
    bool refreshed = false;
    for (size_t j = 0; j + 1 < applied.size(); ++j) {
      if (applied[j].step.effect == "outliers" || applied[j].extra <= 0) continue;  // other data, not nested
      std::vector<Applied> without = applied;
      without.erase(without.begin() + static_cast<long>(j));
      const Problem reduced = build(without);
      const IdentificationResult reduced_fit = fit_of(reduced);
      const double rss = ResidualSquares(fit.residuals), rss_reduced = ResidualSquares(reduced_fit.residuals);
      const double dof = std::max(1.0, 3.0 * static_cast<double>(fit.residuals.size()) - fit.calibration.layout.NumFree());
      const double f = ((rss_reduced - rss) / applied[j].extra) / (rss / dof);
      const boost::math::fisher_f_distribution<double> dist(applied[j].extra, dof);
      const double p = f > 0 ? boost::math::cdf(boost::math::complement(dist, f)) : 1.0;
      if (p < alpha_step) {
        refreshed = reestimate(applied, j, alpha_step) || refreshed;
        continue;
      }
      d.notes.push_back(fmt::format("step {}: {}{} dropped, the later effects explain it (p = {:.2g})", step,
                                    applied[j].step.effect, applied[j].step.component.empty() ? "" : " " + applied[j].step.component, p));
      applied = without;
      problem = reduced;
      fit = reduced_fit;
      validation = held_out(fit.calibration, problem.validate);
      refreshed = false;
      break;  // one at a time: the others are judged again at the next step
    }
    if (refreshed) {
      problem = build(applied);
      fit = fit_of(problem);
      validation = held_out(fit.calibration, problem.validate);
    }
  }
  for (const Applied& a : applied) d.steps.push_back(a.step);

  if (turns_testable && step <= kMostSteps) {
    // The identification data fit to noise now: do the held-out placements turn about their first tiles?
    const double alpha_step = options.alpha / std::pow(2.0, step);
    std::optional<DriftCorrection> drift;
    for (const Applied& a : applied) {
      if (a.step.effect != "thermal_drift") continue;
      const ParameterLayout& fitted = fit.calibration.layout;
      drift = DriftCorrection{CoefficientColumns(fitted, fit.calibration.values, fitted.FreeNames(), problem.identify,
                                                 problem.anchor == Anchor::kFirstTile),
                              DriftColumns(problem.identify, a.tau_s), a.tau_s};
    }
    TurnTest turn = TestHeldOutTurns(fit.calibration, problem.validate, base_options.frame, drift, alpha_step);
    if (applied.empty()) d.candidates.push_back(turn.score);
    if (turn.score.significant) {
      DiagnosisStep s;
      s.effect = "frame_rotation";
      s.component = "z";
      double yaw_sq = 0, u_sq = 0;
      for (const PlacementTurn& t : turn.turns) {
        const Eigen::Vector3d u = t.predicted.diagonal().cwiseMax(0.0).cwiseSqrt();
        const std::string name = static_cast<size_t>(t.group) < validate.groups.size() ? validate.groups[static_cast<size_t>(t.group)]
                                                                                      : std::to_string(t.group);
        d.turns.push_back({name, t.rotation, u});
        yaw_sq += t.rotation.z() * t.rotation.z();
        u_sq += u.z() * u.z();
      }
      // The rms yaw over the placements less what their own noise adds, and the standard uncertainty of that rms.
      const double count = static_cast<double>(std::max<size_t>(1, turn.turns.size()));
      s.size = std::sqrt(std::max(0.0, yaw_sq - u_sq) / count) * 1e6;
      s.size_u = std::sqrt(u_sq / count / count) * 1e6;
      s.size_unit = "urad";
      s.before = s.after = Summarize(fit.residuals);
      s.validation_before = validation;
      s.validation_after = Summarize(turn.residuals_after);
      s.candidates = {turn.score};
      const std::vector<std::string> turn_terms = TurnCoefficients(fit.calibration.layout);
      std::string terms;
      for (const std::string& t : turn_terms) terms += (terms.empty() ? "" : ", ") + t;
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
                            "{}.", terms));
      validation = s.validation_after;
      d.steps.push_back(s);
    }
  }

  d.residuals_after = fit.residuals;
  d.after = Summarize(fit.residuals);
  d.validation_after = d.steps.empty() ? d.validation_before : validation;
  if (d.steps.empty()) {
    d.explanation = "No listed effect explains the residuals better than noise: the model fits these data to " +
                    fmt::format("{:.2f} um rms, and no candidate passes the F-test at the {:.0f} % level with a lower BIC.",
                                d.before.rms_mm * 1e3, options.alpha * 100);
    if (!d.notes.empty()) d.explanation += " " + d.notes.front() + ".";
    return d;
  }
  const DiagnosisStep& first = d.steps.front();
  d.effect = first.effect;
  d.component = first.component;
  d.explanation = first.explanation;
  d.size = first.size;
  d.size_u = first.size_u;
  d.size_unit = first.size_unit;
  return d;
}

}  // namespace fvm::stage
