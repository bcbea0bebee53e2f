#pragma once
// frame_rotation on the held-out placements, the discrepancy workflow's turn test: each placement's turn about its
// first tile, fitted to the calibration's residuals (PlacementTurns) and tested against what the calibration's
// covariance and the noise predict for it when there is no turn.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "stage/calibration.h"
#include "stage/discrepancy.h"
#include "stage/stitched_frame.h"
#include "stage/validation.h"

namespace fvm::stage {

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

TurnTest TestHeldOutTurns(const Calibration& calibration, const MeasurementSet& validate, StitchedFrame frame,
                          const std::optional<DriftCorrection>& drift, double alpha_each);

// The diagnosis step a significant turn test makes: the rms yaw (less what the noise adds) with its uncertainty,
// the residuals with each placement's turn taken out, and what to do about it with this `layout`. Each placement's
// turn goes to `turns`, named by `groups`. `fit` and `validation`: the identification and held-out residuals so far.
DiagnosisStep FrameRotationStep(const TurnTest& turn, const ParameterLayout& layout, const ResidualSummary& fit,
                                const ResidualSummary& validation, const std::vector<std::string>& groups,
                                std::vector<PlacementTurnFinding>* turns);

}  // namespace fvm::stage
