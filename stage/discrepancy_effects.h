#pragma once
// The pieces of the discrepancy workflow (stage/discrepancy.h) that its forward selection puts together: a candidate
// effect scored on the current fit, an effect applied with the values it was estimated at, and the problem (model and
// data) that every applied effect makes. Internal to stage/discrepancy.cc.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "stage/discrepancy.h"
#include "stage/discrepancy_scoring.h"
#include "stage/identification.h"

namespace fvm::stage::discrepancy {

struct Candidate {
  EffectScore score;
  LinearScore linear;
  std::vector<std::string> coefficient_names;  // higher_order, z_coupling
  std::vector<int> flagged;                    // outliers: observation indices
  double tau_s = 0.0;                          // thermal_drift: 0 linear, else the warm-up's time constant
};

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

// Whether the candidate passes its F test at `alpha_each` with a lower BIC (sets score.significant and p_value).
void Test(Candidate& c, double alpha_each);
// The base model and data with every applied effect.
Problem Build(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate, Anchor anchor,
              const std::vector<Applied>& applied);
std::vector<Candidate> ScoreCandidates(const Problem& p, const IdentificationResult& fit, const ParameterLayout& base_layout,
                                       const std::vector<Applied>& applied, const IdentificationOptions& base_options,
                                       double alpha);
Applied MakeApplied(const Candidate& c, const Problem& p, const IdentificationResult& fit);
void FinishCoefficientEffect(Applied& a, const ParameterLayout& before, const Calibration& refit);
double ResidualSquares(const std::vector<Eigen::Vector3d>& residuals);
std::string Named(const Candidate& c);
std::pair<const Candidate*, double> MostlyThePatternOf(const Candidate& c, const std::vector<const Candidate*>& refused);

}  // namespace fvm::stage::discrepancy
