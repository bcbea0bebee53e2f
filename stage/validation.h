#pragma once
// How well a calibration predicts measurements it was not fitted to.
//
// Every validation measurement is referenced to its own first tile (the instrument anchors each stitched
// measurement there, [Pérez 2019] 1.2) whatever anchoring identification used: a constant offset common to a
// measurement is not a stage error the calibration can be blamed for. Its turn is (stitched_frame.h) where the model
// can tell it; and the figures no frame changes (rigid fit per measurement, distances) judge the calibration beside it.

#include <Eigen/Core>
#include <vector>

#include "stage/calibration.h"
#include "stage/identification.h"
#include "stage/residual_summary.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

struct ValidationStats : ResidualSummary {
  double predicted_rms_mm = 0;  // what the calibration's covariance and noise predict for rms_mm
  // What the coefficients identification fixed as undetermined may add (in quadrature): UndeterminedRms, filled in
  // where it is reported (fvm calibrate's judgement); Validate leaves it 0. Apart from predicted_rms_mm: on exports
  // turned at their first tiles the prior of pitch and roll overstates it (the sample: 1.50 -> 1.99 um predicted
  // against 1.37 observed).
  double undetermined_rms_mm = 0;
  std::vector<Eigen::Vector3d> residuals;
  std::vector<Eigen::MatrixXd> jacobians;  // d(residual) / d(free coefficients) of each, with a calibration
  // How the turn of each measurement's stitched frame entered (rotated frame, with a calibration):
  //   "none"         translated frame, or no calibration;
  //   "model"        the model's own rotation terms turn each frame (turn_coefficients), their covariance
  //                  included in the prediction;
  //   "uncertainty"  the model cannot tell one first tile's turn from another's: the prediction includes the
  //                  spread of the turns the measurements show about their first tiles (turn_u_rad, per axis).
  std::string turn = "none";
  std::vector<std::string> turn_coefficients;
  // Rotated frame: the spread of the turns the measurements show about their first tiles beyond what noise and the
  // model's covariance explain (PlacementTurns), per axis; the prediction carries it. About zero where the model
  // tells the turn; the pitch and roll a flat artefact cannot determine, or the whole turn, where it cannot.
  Eigen::Vector3d turn_u_rad = Eigen::Vector3d::Zero();
};

// The first-tile figure: every measurement in its own first tile's frame (stitched_frame.h), the residual
// a + T (F(q) - F(a)) - s. `anchors[g]` is the first tile of observation group g; without anchors (data not
// referenced to a first tile, such as laser-tracker readings) the residual is F(q) - s. A null calibration means
// "no compensation".
ValidationStats Validate(const Calibration* calibration, const std::vector<Observation>& observations,
                         const std::vector<Eigen::Vector3d>& anchors, StitchedFrame frame = StitchedFrame::kTranslated);

// The rms over `observations` (mm) of what the coefficients identification fixed as undetermined may add to Validate's
// prediction: their plausible spread less what the free ones took up of it (stage/undetermined_spread.h), in the same
// frames; 0 where it fixed none. Apart from Validate, which every Monte Carlo run and discrepancy step calls.
double UndeterminedRms(const Calibration& calibration, const std::vector<Observation>& observations,
                       const std::vector<Eigen::Vector3d>& anchors, StitchedFrame frame = StitchedFrame::kTranslated);

// Each measurement's turn about its first tile fitted to a validation's residuals (FitTurn), with the covariance
// the fitted turn would have if there were no turn: the noise and the calibration's covariance propagated through
// the fit. Diagnosis tests them (frame_rotation); the first-tile prediction carries their excess spread.
struct PlacementTurn {
  int group = 0;
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();    // rad
  Eigen::Matrix3d predicted = Eigen::Matrix3d::Zero();   // rad^2, under "no turn": noise + model
  Eigen::Matrix3d noise = Eigen::Matrix3d::Zero();       // rad^2, the noise's part alone
  Eigen::MatrixXd sensitivity;  // 3 x n: d(turn) / d(free coefficients); the model's errors are common to all
                                // placements, so their turns are correlated through it
  Eigen::MatrixXd solve;        // 3 x 3m: the turn from the placement's m stacked residuals (least squares)
  std::vector<size_t> observations;                      // indices into the validation's observations
  std::vector<Eigen::Vector3d> arms;                     // s - a of each
};
std::vector<PlacementTurn> PlacementTurns(const Calibration& calibration, const ValidationStats& validation,
                                          const std::vector<Observation>& observations,
                                          const std::vector<Eigen::Vector3d>& anchors);

// A figure no choice of frame changes, with its prediction from the calibration's covariance and noise.
struct FrameFreeStats {
  int count = 0;  // residual vectors (rigid) or distances
  double rms_mm = 0, max_mm = 0, predicted_rms_mm = 0;
};
// Residuals after the best rigid transform (rotation and translation, [Umeyama 1991]) of each measurement's compensated
// points onto its stitched ones. The prediction projects the model's covariance onto what no rigid motion takes.
FrameFreeStats RigidValidation(const Calibration* calibration, const std::vector<Observation>& observations);
// Errors of the distances between every two points of a measurement (compensated - stitched).
FrameFreeStats PairDistanceValidation(const Calibration* calibration, const std::vector<Observation>& observations);

// Errors of the distances from the first observation of each group to every other one (compensated free
// distance - stitched distance), mm: anchor-free, [Pérez 2019]'s figure of merit (Figs. 6 and 8).
std::vector<double> DistanceErrors(const Calibration* calibration, const std::vector<Observation>& observations);

}  // namespace fvm::stage
