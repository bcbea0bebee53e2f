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

#include "stage/discrepancy_effects.h"
#include "stage/discrepancy_scoring.h"
#include "stage/held_out_turn_test.h"
#include "stage/outlier_flagging.h"
#include "stage/residual_findings.h"
#include "stage/stitched_frame.h"
#include "stage/unexplained_remainder.h"
#include "stage/validation.h"

namespace fvm::stage {
namespace discrepancy {

// The forward selection of Diagnose and its state from step to step: the effects applied, the problem they make,
// its fit and the held-out residual, and the candidates of the last step.
class EffectSelection {
 public:
  EffectSelection(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate,
                  const DiagnosisOptions& options)
      : layout_(layout), identify_(identify), validate_(validate), options_(options), base_(options.identification),
        turns_testable_(!validate.observations.empty() && !validate.anchors.empty()), problem_(BuildWith({})),
        fit_(FitOf(problem_)) {}

  // The base model: its residuals, findings and held-out figure.
  void Start() {
    d_.residuals_before = fit_.residuals;
    d_.before = Summarize(fit_.residuals);
    d_.validation_before = HeldOut(fit_.calibration, problem_.validate);
    d_.findings = Findings(fit_.residuals, identify_, RobustSigma(fit_.residuals, base_.noise_floor_mm));
    validation_ = d_.validation_before;
  }

  // Step `step` of the forward selection, then the backward check; false when no candidate was accepted.
  bool Step(int step) {
    // Alpha spending: step k may raise a false alarm with probability alpha / 2^k at most.
    const double alpha_step = options_.alpha / std::pow(2.0, step);
    candidates_ = ScoreCandidates(problem_, fit_, layout_, applied_, base_, alpha_step);
    const double alpha_each = alpha_step / static_cast<double>(std::max<size_t>(1, candidates_.size() + (turns_testable_ ? 1 : 0)));
    for (Candidate& c : candidates_) Test(c, alpha_each);
    std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
      if (a.score.significant != b.score.significant) return a.score.significant;
      return a.score.delta_bic < b.score.delta_bic;
    });
    std::vector<EffectScore> scores;
    for (const Candidate& c : candidates_) scores.push_back(c.score);
    if (step == 1) d_.candidates = scores;
    refused_.clear();
    bool accepted = false;
    for (const Candidate& c : candidates_) {
      if (!c.score.significant) break;
      if ((accepted = TryCandidate(c, step, alpha_step, scores))) break;
    }
    if (!accepted) return false;
    refused_.clear();  // refused before the accepted one: the next step scores them again on what is left
    DropRedundant(step, alpha_step);
    return true;
  }

  // After the selection: what is left, and whether the held-out placements turn about their first tiles.
  Diagnosis Finish(int step) {
    for (const Applied& a : applied_) d_.steps.push_back(a.step);
    std::vector<std::string> refused_now;
    for (const Candidate* c : refused_) refused_now.push_back(Named(*c));
    const Remainder remainder = JudgeRemainder(fit_.residuals, fit_.calibration.layout.NumFree(), problem_.identify,
                                               refused_now, ever_refused_, validation_);
    d_.unexplained = remainder.unexplained;
    // Where the data do not fit to noise, nothing else is named for what is left: the turn of the held-out frames,
    // above all, would take the pattern a drift leaves on placements measured in order.
    if (remainder.fits_noise && turns_testable_ && step <= kMostSteps) TestTurns(step);
    d_.residuals_after = fit_.residuals;
    d_.after = Summarize(fit_.residuals);
    d_.validation_after = d_.steps.empty() ? d_.validation_before : validation_;
    return std::move(d_);
  }

  static constexpr int kMostSteps = 6;

 private:
  IdentificationResult FitOf(const Problem& p) const {
    IdentificationOptions o = base_;
    o.anchor = p.anchor;
    o.anchors = p.identify.anchors;
    return Identify(p.layout, p.identify.observations, o);
  }
  ResidualSummary HeldOut(const Calibration& cal, const MeasurementSet& set) const {
    if (set.observations.empty()) return ResidualSummary{};
    return static_cast<ResidualSummary>(Validate(&cal, set.observations, set.anchors, base_.frame));
  }
  Problem BuildWith(const std::vector<Applied>& applied) const {
    return Build(layout_, identify_, validate_, base_.anchor, applied);
  }
  void Refuse(const Candidate& c) {
    refused_.push_back(&c);
    if (std::find(ever_refused_.begin(), ever_refused_.end(), Named(c)) == ever_refused_.end()) ever_refused_.push_back(Named(c));
  }

  // A drift or a scale estimated again with every other applied effect in the model: it was estimated before the
  // later ones, and an outlier or a bend may have pulled it. True when the value changed.
  bool Reestimate(std::vector<Applied>& list, size_t j, double alpha) const {
    const std::string effect = list[j].step.effect;
    if (effect != "thermal_drift" && effect != "scale") return false;
    std::vector<Applied> without = list;
    without.erase(without.begin() + static_cast<long>(j));
    const Problem reduced = BuildWith(without);
    const IdentificationResult reduced_fit = FitOf(reduced);
    for (const Candidate& c : ScoreCandidates(reduced, reduced_fit, layout_, without, base_, alpha)) {
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
  }

  // Applies `c` when the held-out placements agree; else notes why not and refuses it.
  bool TryCandidate(const Candidate& c, int step, double alpha_step, const std::vector<EffectScore>& scores) {
    Applied a = MakeApplied(c, problem_, fit_);
    std::vector<Applied> with = applied_;
    with.push_back(a);
    for (size_t j = 0; j + 1 < with.size(); ++j) Reestimate(with, j, alpha_step);
    const Problem next = BuildWith(with);
    const IdentificationResult refit = FitOf(next);
    const ResidualSummary next_validation = HeldOut(refit.calibration, next.validate);
    // Held-out placements must not get worse (beyond their own scatter): otherwise the effect fitted noise.
    if (validation_.count > 0 && next_validation.mean_mm > 1.05 * validation_.mean_mm) {
      // Why it may fail: an effect whose pattern the model's terms nearly take is estimated from what little is
      // its own. A drift along bars measured in order is the usual case, and the design is the cure.
      const bool drift = c.score.effect == "thermal_drift";
      d_.notes.push_back(fmt::format("step {}: {} fits the identification data better but makes the held-out placements "
                                     "worse ({:.2f} -> {:.2f} um; {:.0f} % of its pattern is its own, the rest the model "
                                     "can take){}; the next candidate was tried",
                                     step, Named(c),
                                     validation_.mean_mm * 1e3, next_validation.mean_mm * 1e3, 100 * c.linear.own,
                                     drift ? ". A drift grows along each bar as its calottes are measured in order, like "
                                             "anything else that grows along it; measuring every other placement "
                                             "backwards shows the drift at the shared start"
                                           : ""));
      Refuse(c);
      return false;
    }
    // An effect that is mostly the pattern of one the held-out placements refused would take what that one left
    // behind; it is named only where it predicts the held-out placements clearly better (by a fifth) on its own.
    if (const auto [other, share] = MostlyThePatternOf(c, refused_);
        other != nullptr && validation_.count > 0 && next_validation.mean_mm > 0.8 * validation_.mean_mm) {
      d_.notes.push_back(fmt::format("step {}: {} fits the identification data better, but {:.0f} % of what it explains "
                                     "there is the pattern of the refused {}, and the held-out placements barely change "
                                     "({:.2f} -> {:.2f} um): it would take what that one leaves; not named",
                                     step, Named(c), 100 * share, Named(*other), validation_.mean_mm * 1e3,
                                     next_validation.mean_mm * 1e3));
      Refuse(c);
      return false;
    }
    if (!a.coefficient_names.empty()) FinishCoefficientEffect(a, problem_.layout, refit.calibration);
    a.step.before = Summarize(fit_.residuals);
    a.step.after = Summarize(refit.residuals);
    a.step.validation_before = validation_;
    a.step.validation_after = next_validation;
    a.step.candidates = scores;
    for (const Candidate& other : candidates_) {
      const double explained = c.linear.rss_base - c.linear.rss;
      if (&other == &c || other.linear.extra != c.linear.extra || !other.score.significant ||
          std::abs(other.linear.rss - c.linear.rss) > 1e-3 * explained) {
        continue;
      }
      a.step.alternatives.push_back(other.score.effect + (other.score.component.empty() ? "" : " " + other.score.component));
    }
    with.back() = a;
    applied_ = with;
    problem_ = next;
    fit_ = refit;
    validation_ = next_validation;
    return true;
  }

  // Backward check: an earlier effect the later ones made redundant no longer earns its parameters.
  void DropRedundant(int step, double alpha_step) {
    bool refreshed = false;
    for (size_t j = 0; j + 1 < applied_.size(); ++j) {
      if (applied_[j].step.effect == "outliers" || applied_[j].extra <= 0) continue;  // other data, not nested
      std::vector<Applied> without = applied_;
      without.erase(without.begin() + static_cast<long>(j));
      const Problem reduced = BuildWith(without);
      const IdentificationResult reduced_fit = FitOf(reduced);
      const double rss = ResidualSquares(fit_.residuals), rss_reduced = ResidualSquares(reduced_fit.residuals);
      const double dof = std::max(1.0, 3.0 * static_cast<double>(fit_.residuals.size()) - fit_.calibration.layout.NumFree());
      const double f = ((rss_reduced - rss) / applied_[j].extra) / (rss / dof);
      const boost::math::fisher_f_distribution<double> dist(applied_[j].extra, dof);
      const double p = f > 0 ? boost::math::cdf(boost::math::complement(dist, f)) : 1.0;
      if (p < alpha_step) {
        refreshed = Reestimate(applied_, j, alpha_step) || refreshed;
        continue;
      }
      d_.notes.push_back(fmt::format("step {}: {}{} dropped, the later effects explain it (p = {:.2g})", step,
                                     applied_[j].step.effect, applied_[j].step.component.empty() ? "" : " " + applied_[j].step.component, p));
      applied_ = without;
      problem_ = reduced;
      fit_ = reduced_fit;
      validation_ = HeldOut(fit_.calibration, problem_.validate);
      refreshed = false;
      break;  // one at a time: the others are judged again at the next step
    }
    if (refreshed) {
      problem_ = BuildWith(applied_);
      fit_ = FitOf(problem_);
      validation_ = HeldOut(fit_.calibration, problem_.validate);
    }
  }

  // The identification data fit to noise now: do the held-out placements turn about their first tiles?
  void TestTurns(int step) {
    const double alpha_step = options_.alpha / std::pow(2.0, step);
    std::optional<DriftCorrection> drift;
    for (const Applied& a : applied_) {
      if (a.step.effect != "thermal_drift") continue;
      const ParameterLayout& fitted = fit_.calibration.layout;
      drift = DriftCorrection{CoefficientColumns(fitted, fit_.calibration.values, fitted.FreeNames(), problem_.identify,
                                                 problem_.anchor == Anchor::kFirstTile),
                              DriftColumns(problem_.identify, a.tau_s), a.tau_s};
    }
    TurnTest turn = TestHeldOutTurns(fit_.calibration, problem_.validate, base_.frame, drift, alpha_step);
    if (applied_.empty()) d_.candidates.push_back(turn.score);
    const std::optional<TurnsRefused> refused_turns =
        turn.score.significant ? DriftInsteadOfTurns(fit_.calibration, problem_.validate, base_.frame, turn.residuals_after,
                                                     {step, turn.score.p_value, drift.has_value()}, validation_,
                                                     Summarize(fit_.residuals), alpha_step)
                               : std::nullopt;
    if (refused_turns) {
      d_.notes.push_back(refused_turns->note);
      d_.unexplained = refused_turns->unexplained;
    } else if (turn.score.significant) {
      d_.steps.push_back(FrameRotationStep(turn, fit_.calibration.layout, Summarize(fit_.residuals), validation_,
                                           validate_.groups, &d_.turns));
      validation_ = d_.steps.back().validation_after;
    }
  }

  const ParameterLayout& layout_;
  const MeasurementSet& identify_;
  const MeasurementSet& validate_;
  const DiagnosisOptions& options_;
  const IdentificationOptions& base_;
  const bool turns_testable_;
  Diagnosis d_;
  std::vector<Applied> applied_;
  Problem problem_;
  IdentificationResult fit_;
  ResidualSummary validation_;
  std::vector<Candidate> candidates_;        // the last step's, scored on the residuals left
  std::vector<const Candidate*> refused_;    // the last step's significant candidates that were not accepted
  std::vector<std::string> ever_refused_;    // every candidate refused at any step, by name, in order
};

// The first accepted effect is the diagnosis' headline; without one, why none is named.
static void Explain(Diagnosis& d, double alpha) {
  if (d.steps.empty()) {
    if (!d.unexplained.empty()) {
      d.explanation = "No effect is named; " + d.unexplained + ".";
      return;
    }
    d.explanation = "No listed effect explains the residuals better than noise: the model fits these data to " +
                    fmt::format("{:.2f} um rms, and no candidate passes the F-test at the {:.0f} % level with a lower BIC.",
                                d.before.rms_mm * 1e3, alpha * 100);
    if (!d.notes.empty()) d.explanation += " " + d.notes.front() + ".";
    return;
  }
  const DiagnosisStep& first = d.steps.front();
  d.effect = first.effect;
  d.component = first.component;
  d.explanation = first.explanation;
  d.size = first.size;
  d.size_u = first.size_u;
  d.size_unit = first.size_unit;
}

}  // namespace discrepancy

Diagnosis Diagnose(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate,
                   const DiagnosisOptions& options) {
  discrepancy::EffectSelection selection(layout, identify, validate, options);
  selection.Start();
  int step = 1;
  while (step <= discrepancy::EffectSelection::kMostSteps && selection.Step(step)) ++step;
  Diagnosis d = selection.Finish(step);
  discrepancy::Explain(d, options.alpha);
  return d;
}

}  // namespace fvm::stage
