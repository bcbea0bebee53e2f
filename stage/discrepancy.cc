#include "stage/discrepancy.h"

#include <fmt/core.h>

#include <Eigen/QR>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <functional>
#include <map>

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
  int extra = 0;       // rank the candidate adds
  int rank = 0;        // rank of base + candidate
  Eigen::VectorXd effect;      // least-squares values of the candidate's columns (in the columns' units)
  Eigen::VectorXd effect_u;    // their standard uncertainties
};

// Extra sum of squares of the candidate columns over the base model, on the linearised problem.
//
// A candidate column built from measured coordinates (a scale acts on s - a) carries their noise. When the base
// model already spans its smooth part, what is left is that noise, and it correlates with the residual's own
// noise: a false "effect". Only the part of a candidate that the base model leaves above 1e-4 of its norm counts
// as new; centre noise of 0.5 um on coordinates of about 100 mm is 5e-6 of it, so this keeps a 20x margin.
LinearScore ScoreColumns(const Eigen::VectorXd& r0, const Eigen::MatrixXd& base, const Eigen::MatrixXd& extra) {
  constexpr double kNewDirection = 1e-4;
  LinearScore s;
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
  for (Eigen::Index c = 0; c < unique.cols(); ++c) {
    if (unique.col(c).norm() < kNewDirection) unique.col(c).setZero();
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

struct Candidate {
  EffectScore score;
  LinearScore linear;
  std::vector<std::string> coefficient_names;  // higher_order, z_coupling
  std::vector<int> flagged;                    // outliers: observation indices
};

void Test(Candidate& c, double m, double alpha_each) {
  const LinearScore& l = c.linear;
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
// it when there is no turn: chi^2 of the turns over the directions a placement determines (a bar shows nothing of
// a turn about its own length).
struct TurnTest {
  EffectScore score{"frame_rotation", "", 0, 0.0, 1.0, 0.0, false};
  std::vector<PlacementTurn> turns;
  std::vector<Eigen::Vector3d> residuals_after;  // with each placement's turn taken out
};

TurnTest TestHeldOutTurns(const Calibration& calibration, const MeasurementSet& validate, StitchedFrame frame,
                          double alpha_each) {
  TurnTest t;
  const ValidationStats v = Validate(&calibration, validate.observations, validate.anchors, frame);
  t.turns = PlacementTurns(calibration, v, validate.observations, validate.anchors);
  t.residuals_after = v.residuals;
  double chi2 = 0.0;
  int dof = 0;
  for (const PlacementTurn& turn : t.turns) {
    for (size_t k = 0; k < turn.observations.size(); ++k) {
      t.residuals_after[turn.observations[k]] -= TurnDisplacement(turn.rotation, turn.arms[k]);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(turn.predicted);
    for (int k = 0; k < 3; ++k) {
      const double lambda = eigen.eigenvalues()[k];
      if (lambda <= 1e-9 * eigen.eigenvalues().maxCoeff()) continue;  // a direction the placement does not show
      chi2 += std::pow(eigen.eigenvectors().col(k).dot(turn.rotation), 2) / lambda;
      ++dof;
    }
  }
  if (dof == 0) return t;
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

}  // namespace

Diagnosis Diagnose(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate,
                   const DiagnosisOptions& options) {
  Diagnosis d;
  const IdentificationOptions& base_options = options.identification;
  const bool anchored = base_options.anchor == Anchor::kFirstTile;
  const auto identify_with = [&](const ParameterLayout& l, const MeasurementSet& set, Anchor anchor) {
    IdentificationOptions o = base_options;
    o.anchor = anchor;
    o.anchors = set.anchors;
    return Identify(l, set.observations, o);
  };
  const IdentificationResult base = identify_with(layout, identify, base_options.anchor);
  d.residuals_before = base.residuals;
  d.before = Summarize(base.residuals);
  const auto validation = [&](const Calibration& cal, const MeasurementSet& set) {
    if (set.observations.empty()) return ResidualSummary{};
    return static_cast<ResidualSummary>(Validate(&cal, set.observations, set.anchors, base_options.frame));
  };
  d.validation_before = validation(base.calibration, validate);

  const Eigen::VectorXd r0 = Stack(base.residuals);
  const double m = static_cast<double>(r0.size());
  const ParameterLayout& fitted = base.calibration.layout;
  const Eigen::MatrixXd jb = CoefficientColumns(fitted, base.calibration.values, fitted.FreeNames(), identify, anchored);
  const Eigen::Index rows = r0.size();

  std::vector<Candidate> candidates;
  // Coefficients added to the model: higher orders, pitch and roll.
  const auto coefficient_candidate = [&](const std::string& effect, const std::string& component,
                                         const std::function<void(ParameterLayout&)>& extend) {
    ParameterLayout extended = fitted;
    extend(extended);
    std::vector<std::string> added;
    for (const std::string& name : extended.FreeNames()) {
      if (fitted.FreeIndexOf(name) < 0) added.push_back(name);
    }
    if (added.empty()) return;
    const std::vector<double> values = ValuesByName(fitted, base.calibration.values, extended);
    Candidate c{{effect, component}, ScoreColumns(r0, jb, CoefficientColumns(extended, values, added, identify, anchored)), added, {}};
    candidates.push_back(std::move(c));
  };
  for (int t = 0; t < kFirstSquarenessTerm; ++t) {
    const TermSpec& spec = layout.term(t);
    if (!spec.present || spec.order >= kMaxOrder) continue;
    const std::string term(GetErrorTerm(t).vdi);
    coefficient_candidate("higher_order", term, [&](ParameterLayout& l) { RaiseOrder(l, term); });
  }
  coefficient_candidate("z_coupling", "", AddPitchAndRoll);

  const auto column_candidate = [&](const std::string& effect, const std::string& component, const Eigen::MatrixXd& columns) {
    candidates.push_back(Candidate{{effect, component}, ScoreColumns(r0, jb, columns), {}, {}});
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
  if (!identify.t_s.empty()) {
    Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 3);
    for (size_t i = 0; i < identify.observations.size(); ++i) {
      for (int c = 0; c < 3; ++c) columns(3 * static_cast<Eigen::Index>(i) + c, c) = -identify.t_s[i];
    }
    column_candidate("thermal_drift", "", columns);
  }
  if (!identify.anchors.empty()) {  // a scale about the first tile needs one
    Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 1);
    for (size_t i = 0; i < identify.observations.size(); ++i) {
      const Observation& o = identify.observations[i];
      const Eigen::Vector3d a = identify.anchors[static_cast<size_t>(o.group)];
      columns.block<2, 1>(3 * static_cast<Eigen::Index>(i), 0) = -(o.measured - a).head<2>();
    }
    column_candidate("scale", "xy", columns);
  }
  // Noise per coordinate that a few blunders cannot inflate: the median absolute residual (MAD) scaled to sigma.
  std::vector<double> components;
  for (const Eigen::Vector3d& r : base.residuals) components.insert(components.end(), {std::abs(r.x()), std::abs(r.y()), std::abs(r.z())});
  std::nth_element(components.begin(), components.begin() + static_cast<long>(components.size() / 2), components.end());
  const double robust_sigma = std::max(1.4826 * components[components.size() / 2], base_options.noise_floor_mm);
  {
    // Outliers: centres whose error is improbable for Gaussian noise of the robust scale, Bonferroni over centres.
    const double sigma = robust_sigma;
    const boost::math::chi_squared_distribution<double> chi2(3.0);
    const double limit = boost::math::quantile(boost::math::complement(chi2, options.alpha / static_cast<double>(base.residuals.size())));
    Candidate c{{"outliers", ""}, {}, {}, {}};
    for (size_t i = 0; i < base.residuals.size(); ++i) {
      if (base.residuals[i].squaredNorm() / (sigma * sigma) > limit) c.flagged.push_back(static_cast<int>(i));
    }
    if (!c.flagged.empty()) {
      Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 3 * static_cast<Eigen::Index>(c.flagged.size()));
      for (size_t k = 0; k < c.flagged.size(); ++k) {
        for (int j = 0; j < 3; ++j) columns(3 * c.flagged[k] + j, 3 * static_cast<Eigen::Index>(k) + j) = 1.0;
      }
      c.linear = ScoreColumns(r0, jb, columns);
      candidates.push_back(std::move(c));
    }
  }

  const bool turns_testable = !validate.observations.empty() && !validate.anchors.empty();
  const double alpha_each = options.alpha / static_cast<double>(std::max<size_t>(1, candidates.size() + (turns_testable ? 1 : 0)));
  for (Candidate& c : candidates) Test(c, m, alpha_each);
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.score.significant != b.score.significant) return a.score.significant;
    return a.score.delta_bic < b.score.delta_bic;
  });
  for (const Candidate& c : candidates) d.candidates.push_back(c.score);
  d.findings = Findings(base.residuals, identify, robust_sigma);
  d.residuals_after = base.residuals;
  d.after = d.before;
  d.validation_after = d.validation_before;
  if (candidates.empty() || !candidates.front().score.significant) {
    if (turns_testable) {
      // The identification data fit to noise: do the held-out placements turn about their first tiles?
      TurnTest turn = TestHeldOutTurns(base.calibration, validate, base_options.frame, alpha_each);
      d.candidates.push_back(turn.score);
      if (turn.score.significant) {
        d.effect = "frame_rotation";
        d.component = "z";
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
        d.size = std::sqrt(std::max(0.0, yaw_sq - u_sq) / count) * 1e6;
        d.size_u = std::sqrt(u_sq / count / count) * 1e6;
        d.size_unit = "urad";
        d.validation_after = Summarize(turn.residuals_after);
        const std::vector<std::string> turn_terms = TurnCoefficients(base.calibration.layout);
        std::string terms;
        for (const std::string& t : turn_terms) terms += (terms.empty() ? "" : ", ") + t;
        d.explanation = fmt::format(
            "The held-out placements' residuals grow perpendicular to, and in proportion to, their distance from the "
            "first tile: each stitched measurement is turned about its first tile ({:.1f} +- {:.1f} urad rms yaw over {} "
            "placements). The instrument registers tiles by translation, so a mosaic keeps the orientation the stage "
            "had at its first tile; identification placements that share a start share that turn and the model's "
            "constant terms absorb it, so only placements that start elsewhere show it. {}",
            d.size, d.size_u, turn.turns.size(),
            turn_terms.empty()
                ? "This model has no rotation terms that vary over the stage: a model of order 1 or more (27, 42) can "
                  "tell the turn at each first tile."
                : fmt::format("fvm calibrate --stitched-frame rotated (the default) turns each placement by the model's own "
                              "{}.", terms));
        return d;
      }
    }
    d.explanation = "No listed effect explains the residuals better than noise: the model fits these data to " +
                    fmt::format("{:.2f} um rms, and no candidate passes the F-test at the {:.0f} % level with a lower BIC.",
                                d.before.rms_mm * 1e3, options.alpha * 100);
    return d;
  }

  // Refit with the winner and measure the gap again, on identification and held-out placements.
  const Candidate& best = candidates.front();
  const std::string& effect = best.score.effect;
  IdentificationResult improved = base;
  MeasurementSet validate_corrected = validate;
  const LinearScore& l = best.linear;
  if (effect == "higher_order" || effect == "z_coupling") {
    ParameterLayout extended = layout;
    if (effect == "higher_order") {
      RaiseOrder(extended, best.score.component);
    } else {
      AddPitchAndRoll(extended);
    }
    improved = identify_with(extended, identify, base_options.anchor);
    // The effect's size: the largest added coefficient the refit could determine.
    const Calibration& cal = improved.calibration;
    const Eigen::VectorXd u = cal.StandardUncertainty();
    std::string name;
    double largest = -1.0;
    for (const std::string& candidate : best.coefficient_names) {
      const int slot = cal.layout.FreeIndexOf(candidate);
      if (slot < 0) continue;
      const DisplayUnit unit = UnitOf(cal.layout.coefficients()[static_cast<size_t>(cal.layout.FindCoefficient(candidate))]);
      const double value = cal.values[static_cast<size_t>(slot)] * unit.per_si;
      if (std::abs(value) > largest) {
        largest = std::abs(value);
        name = candidate;
        d.size = value;
        d.size_u = u[slot] * unit.per_si;
        d.size_unit = unit.name;
      }
    }
    if (name.empty()) name = best.coefficient_names.front();
    d.component = effect == "higher_order" ? best.score.component : name.substr(0, 3);
    d.explanation = effect == "higher_order"
                        ? fmt::format("The {} error of the stage bends more than its order-{} polynomial can follow: adding {} "
                                      "({:.2f} +- {:.2f} {}) takes the residual structure along the axis away.",
                                      d.component, layout.term(*FindErrorTerm(d.component)).order, name, d.size, d.size_u, d.size_unit)
                        : fmt::format("The stage pitches and rolls ({} = {:.1f} +- {:.1f} urad): the artefact was measured at "
                                      "different heights, and a rotation moves the lateral coordinates in proportion to the "
                                      "height, which the model without pitch and roll cannot follow.",
                                      name, d.size, d.size_u);
  } else if (effect == "reference_anchor") {
    improved = identify_with(layout, identify, Anchor::kFirstTile);
    double largest = 0;
    for (Eigen::Index k = 0; k < l.effect.size(); ++k) largest = std::max(largest, std::abs(l.effect[k]));
    d.size = largest * 1e3;
    d.size_u = (l.effect_u.size() ? l.effect_u.maxCoeff() : 0.0) * 1e3;
    d.size_unit = "um";
    d.explanation = fmt::format(
        "The placements did not start at one spot, and the instrument places the first tile of every stitched "
        "measurement by its encoders: each measurement carries the stage error of its own first tile (offsets up to "
        "{:.1f} +- {:.1f} um between placements). Referencing each measurement to its first tile (--anchor first-tile) "
        "removes them.", d.size, d.size_u);
  } else if (effect == "thermal_drift") {
    const Eigen::Vector3d v(l.effect[0], l.effect[1], l.effect[2]);  // mm/s
    Eigen::Index axis = 0;
    v.cwiseAbs().maxCoeff(&axis);
    const auto undrift = [&](const MeasurementSet& set) {
      return Changed(set, [&](Observation& o, size_t i) { o.command -= v * set.t_s[i]; });
    };
    improved = identify_with(layout, undrift(identify), base_options.anchor);
    if (!validate.t_s.empty()) validate_corrected = undrift(validate);
    d.component = std::string(1, "xyz"[axis]);
    d.size = v[axis] * 1e3 * 60.0;
    d.size_u = l.effect_u[axis] * 1e3 * 60.0;
    d.size_unit = "um/min";
    d.explanation = fmt::format(
        "The stitching-free centres drift with measurement time: {:.2f} +- {:.2f} um/min along {} (all axes: {:.2f}, {:.2f}, "
        "{:.2f} um/min), as a stage or column warming up would (000:7130). Removing a drift linear in t takes the "
        "time-correlated residuals away.", d.size, d.size_u, d.component, v.x() * 6e4, v.y() * 6e4, v.z() * 6e4);
  } else if (effect == "scale") {
    const double kappa = -l.effect[0];  // the column is -(s - a): its coefficient undoes the scale
    const auto unscale = [&](const MeasurementSet& set) {
      return Changed(set, [&](Observation& o, size_t) {
        const Eigen::Vector3d a = set.anchors[static_cast<size_t>(o.group)];
        o.measured.head<2>() = a.head<2>() + (o.measured - a).head<2>() / (1.0 + kappa);
      });
    };
    improved = identify_with(layout, unscale(identify), base_options.anchor);
    validate_corrected = unscale(validate);
    d.component = "xy";
    d.size = kappa * 1e6;
    d.size_u = l.effect_u[0] * 1e6;
    d.size_unit = "ppm";
    d.explanation = fmt::format(
        "Stitched distances are scaled by {:.0f} +- {:.0f} ppm about the first tile: a lens (pixel size) or stitching scale "
        "error of the reference. The stage model cannot absorb a scale that restarts at every measurement's first tile.",
        d.size, d.size_u);
  } else if (effect == "outliers") {
    MeasurementSet kept;
    std::vector<std::string> names;
    double largest = 0;
    for (size_t i = 0; i < identify.observations.size(); ++i) {
      if (std::find(best.flagged.begin(), best.flagged.end(), static_cast<int>(i)) != best.flagged.end()) {
        names.push_back(identify.labels.empty() ? std::to_string(i) : identify.labels[i]);
        largest = std::max(largest, base.residuals[i].norm());
        continue;
      }
      kept.observations.push_back(identify.observations[i]);
      if (!identify.t_s.empty()) kept.t_s.push_back(identify.t_s[i]);
      if (!identify.labels.empty()) kept.labels.push_back(identify.labels[i]);
    }
    kept.anchors = identify.anchors;
    improved = identify_with(layout, kept, base_options.anchor);
    d.component = "";
    for (const std::string& n : names) d.component += (d.component.empty() ? "" : ",") + n;
    d.size = largest * 1e3;
    d.size_u = base.calibration.sigma_mm * std::sqrt(3.0) * 1e3;
    d.size_unit = "um";
    d.explanation = fmt::format(
        "{} centre(s) ({}) lie far outside the noise (largest {:.1f} um against {:.2f} um per coordinate): failed sphere "
        "fits, e.g. a burr or missing points in the calotte. Dropping them (or --loss cauchy) restores the fit.",
        names.size(), d.component, d.size, base.calibration.sigma_mm * 1e3);
  }
  d.validation_after = validation(improved.calibration, validate_corrected);
  const ResidualSummary after = Summarize(improved.residuals);
  // Held-out placements must not get worse (beyond their own scatter): otherwise the effect fitted noise.
  if (d.validation_before.count > 0 && d.validation_after.mean_mm > 1.05 * d.validation_before.mean_mm) {
    d.explanation = fmt::format("The best candidate ({}) fits the identification data better but makes the held-out "
                                "placements worse ({:.2f} -> {:.2f} um): no listed effect explains the gap.",
                                effect, d.validation_before.mean_mm * 1e3, d.validation_after.mean_mm * 1e3);
    d.validation_after = d.validation_before;
    d.component.clear();
    d.size = d.size_u = 0;
    d.size_unit.clear();
    return d;
  }
  d.effect = effect;
  d.after = after;
  d.residuals_after = improved.residuals;
  return d;
}

}  // namespace fvm::stage
