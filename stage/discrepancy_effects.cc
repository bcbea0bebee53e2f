#include "stage/discrepancy_effects.h"

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

#include "stage/held_out_turn_test.h"
#include "stage/outlier_flagging.h"
#include "stage/residual_findings.h"
#include "stage/stitched_frame.h"
#include "stage/unexplained_remainder.h"
#include "stage/validation.h"

namespace fvm::stage::discrepancy {
namespace {

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

// "higher_order (xTx)" for messages.
std::string Named(const std::string& effect, const std::string& component) {
  return component.empty() ? effect : effect + " (" + component + ")";
}

bool IsApplied(const std::vector<Applied>& applied, const std::string& effect) {
  return std::any_of(applied.begin(), applied.end(), [&](const Applied& a) { return a.step.effect == effect; });
}

}  // namespace

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
    Candidate c{{"outliers", ""}, {}, {}, FlagOutliers(p.layout, p.identify, p.anchor, fit.residuals, base_options, alpha)};
    if (!c.flagged.empty()) {
      Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(rows, 3 * static_cast<Eigen::Index>(c.flagged.size()));
      for (size_t k = 0; k < c.flagged.size(); ++k) {
        for (int j = 0; j < 3; ++j) columns(3 * c.flagged[k] + j, 3 * static_cast<Eigen::Index>(k) + j) = 1.0;
      }
      c.linear = ScoreColumns(r0, jb, columns, "outliers");
      blunders = c.flagged;
      candidates.push_back(std::move(c));
    }
  }
  const auto score = [&](const Eigen::MatrixXd& columns, const std::string& name) {
    return ScoreColumnsWithout(blunders, r0, jb, columns, name);
  };
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
    candidates.push_back({{effect, component},
                          score(CoefficientColumns(extended, values, added, identify, anchored), Named(effect, component)),
                          added,
                          {}});
  };
  for (int t = 0; t < kFirstSquarenessTerm; ++t) {
    const TermSpec& spec = p.layout.term(t);
    if (!spec.present || spec.order >= kMaxOrder || !base_layout.term(t).present) continue;
    const std::string term(GetErrorTerm(t).vdi);
    coefficient_candidate("higher_order", term, [&](ParameterLayout& l) { RaiseOrder(l, term); });
  }
  coefficient_candidate("z_coupling", "", AddPitchAndRoll);
  const auto column_candidate = [&](const std::string& effect, const std::string& component, const Eigen::MatrixXd& columns) {
    candidates.push_back(Candidate{{effect, component}, score(columns, Named(effect, component)), {}, {}});
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
      const LinearScore l = score(DriftColumns(identify, tau_min * 60.0), "thermal_drift (warm-up)");
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

// A candidate's name as the notes and the steps give it: the effect and its component.
std::string Named(const Candidate& c) {
  return c.score.component.empty() ? c.score.effect : c.score.effect + " " + c.score.component;
}

// The refused candidate whose pattern takes most of what `c` explains in the identification data (the share of c's
// explained sum of squares along it), when that share is more than half; else none.
std::pair<const Candidate*, double> MostlyThePatternOf(const Candidate& c, const std::vector<const Candidate*>& refused) {
  const Eigen::VectorXd& mine = c.linear.explained;
  const Candidate* most = nullptr;
  double most_share = 0.5;
  for (const Candidate* r : refused) {
    const Eigen::VectorXd& theirs = r->linear.explained;
    if (theirs.size() != mine.size() || mine.squaredNorm() <= 0 || theirs.squaredNorm() <= 0) continue;
    const double share = std::pow(mine.dot(theirs), 2) / (mine.squaredNorm() * theirs.squaredNorm());
    if (share > most_share) most = r, most_share = share;
  }
  return {most, most_share};
}

}  // namespace fvm::stage::discrepancy
