#pragma once
// The discrepancy workflow: fit a stage model, study where it and the measurements disagree, name the physical
// effect that explains the disagreement, add it, refit, and show the gap shrink.
//
// Each candidate effect is a block of extra parameters with a physical story (docs/tutorials/discrepancy.md):
//   higher_order      a component needs the next polynomial order (one candidate per component: xTx, yRz, ...)
//   z_coupling        pitch and roll (xRx, xRy, yRx, yRy) that only height changes reveal
//   reference_anchor  each stitched measurement is anchored at the stage error of its own first tile
//   thermal_drift     stitching-free centres drift with measurement time (needs the t column): linearly, or as a
//                     warm-up A + B (1 - exp(-t/tau)) when that beats the linear drift by its own F-test
//   scale             stitched distances are scaled about the first tile (lens or stitching scale)
//   outliers          centres far outside the noise: failed sphere fits
//   frame_rotation    each stitched measurement keeps the orientation the stage had at its first tile
//                     (stitched_frame.h); placements that share a start share the turn, so only held-out ones show it
// Selection is statistical and forward: every candidate is scored on the linearised fit with an F-test (extra sum
// of squares) and BIC; the significant ones are tried best first, and the first whose refit does not make the
// held-out placements worse is accepted. Then the remaining candidates are scored against the new residuals, and
// so on until none passes. Step k tests at alpha / 2^k, Bonferroni over its candidates, so the family-wise
// false-alarm probability over all steps stays below alpha (the sum of alpha / 2^k). After each step, an earlier
// effect that the later ones made redundant (its own F-test no longer significant) is dropped; an accepted drift or
// scale stays free while later candidates are scored. A candidate whose pattern the base model takes to within 1 %
// is no effect of these data (a scale about a shared start is the model's linear terms). When the identification
// data fit to noise, the held-out placements are examined for turns about their first tiles (frame_rotation): a
// chi-square of the fitted turns against what the noise, the calibration's covariance (joint with a drift's, when
// one was corrected) and the coefficients the data could not determine predict for them.
// Outliers are found one at a time, refitting after each, so that a large blunder does not drag good neighbours
// over the limit (swamping); a centre must also stand out from its neighbours along the bar, which an effect the
// model lacks moves with it; and the other candidates are scored without the flagged centres.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "stage/identification.h"
#include "stage/parameter_layout.h"
#include "stage/validation.h"

namespace fvm::stage {

struct DiagnosisOptions {
  double alpha = 0.01;  // family-wise false-alarm probability over all candidates
  IdentificationOptions identification;
};

struct EffectScore {
  std::string effect;
  std::string component;
  int extra_parameters = 0;
  double f_statistic = 0.0;
  double p_value = 1.0;
  double delta_bic = 0.0;
  bool significant = false;
};

// frame_rotation: the turn of one held-out placement about its first tile.
struct PlacementTurnFinding {
  std::string placement;
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();  // small rotation vector; z is the yaw
  Eigen::Vector3d u_rad = Eigen::Vector3d::Zero();         // standard uncertainties (0: not determined, e.g. about a bar's length)
};

// One accepted step of the forward selection.
struct DiagnosisStep {
  std::string effect, component, explanation;
  double size = 0.0, size_u = 0.0;
  std::string size_unit;
  ResidualSummary before, after;                        // identification residuals
  ResidualSummary validation_before, validation_after;  // held-out placements
  std::vector<EffectScore> candidates;                  // as scored at this step, best first
  // Other candidates that explain these data exactly as well (the same extra sum of squares with as many
  // parameters): the data cannot tell them from this one, e.g. a scale and a linear positioning error of Y once X's
  // is in the model. "effect component" each.
  std::vector<std::string> alternatives;
};

struct Diagnosis {
  std::optional<std::string> effect;  // the first accepted effect, or none (the steps hold them all)
  std::string component;
  std::string explanation;
  std::vector<DiagnosisStep> steps;   // every accepted effect, in the order it was added
  std::vector<std::string> notes;     // candidates tried and refused, effects dropped by the backward check
  // When the last step refused candidates that still explain part of the identification residuals significantly:
  // what remains unexplained and its likeliest cause, one sentence (empty when the residuals are noise to the tests).
  std::string unexplained;
  ResidualSummary before, after;                  // identification residuals, base model and with every effect
  ResidualSummary validation_before, validation_after;
  double size = 0.0, size_u = 0.0;                // the first effect's size and its standard uncertainty
  std::string size_unit;
  std::vector<EffectScore> candidates;            // every candidate of the first step, best first
  std::vector<std::string> findings;              // what the residual analysis saw, one sentence each
  std::vector<PlacementTurnFinding> turns;        // frame_rotation: per held-out placement
  std::vector<Eigen::Vector3d> residuals_before;  // identification residuals of the base model, mm
  std::vector<Eigen::Vector3d> residuals_after;   // ... with the effect (base model's when none is accepted)
};

Diagnosis Diagnose(const ParameterLayout& layout, const MeasurementSet& identify, const MeasurementSet& validate,
                   const DiagnosisOptions& options = {});

}  // namespace fvm::stage
