#pragma once
// Peak-locking of the focus peak fit, measured on the stack's own height map and taken off. The power fit's
// vertex errs by a few hundredths of a step depending on where the surface lies between two images (its phase):
// the focus curve is no exact parabola in the transformed measure, so the fit pulls the vertex towards or away from
// the nearest image, the same way for every pixel of a stack, as a sub-pixel peak fit locks onto whole pixels in
// particle image velocimetry [Westerweel 1997]. On a face tilted by a few steps over the field the phase sweeps
// across the map and the error is a periodic function of it (on ../shared/bench/focusgen.py at NA 0.3, sigma0
// 0.3 um, 0.7 px texture: +-0.04 step, 0.042 step rms on the flat of which 0.03 is not phase-locked).
//
// It is observable wherever the surface is nearly level but not level within a step: the heights' departures
// from a smooth local surface (a plane fitted over a box of kPlaneBoxPx, wider than the stripes of equal phase)
// are regressed on harmonics of the phase, the regressors passing through the same local plane (Frisch and Waugh
// 1933: the coefficients are those of the joint fit of the planes and the harmonics), and their covariance from
// the residuals summed over blocks of pixels, whose errors are shared by neighbours (a cluster sandwich, Liang and
// Zeger 1986; the correction's uncertainty takes the larger of those over blocks of two sizes, since errors
// shared across a block's border escape it). The coefficients are shrunk towards zero by the positive-part
// James-Stein factor (James and Stein 1961): a bias no larger than its own noise is hardly taken off. Fitted only on
// level points (kLevelSlope): on slopes a window spans several phases, and at NA 0.9 the bias found on the
// calotte's bottom had the opposite sign of the flat's. The correction fades with the slope as
// exp(-(slope / kFadeSlope)^2).
// Declined (nothing changed) where too few level points or too few phases are seen (a face level within a step:
// its phases are the surface's one phase plus noise, whose regression on the phase would only flatten the noise).
// Used by focus_variation.cc.

#include <array>
#include <string>
#include <vector>

namespace fvm::imaging {

struct PhaseBias {
  static constexpr int kHarmonics = 3;
  static constexpr int kTerms = 2 * kHarmonics;  // cos and sin of 2 pi k phase, k = 1..kHarmonics
  bool applied = false;
  std::string reason;  // why not, when not applied
  int points = 0;      // level points in the fit (on the estimation grid)
  double step_mm = 0.0;
  double shrinkage = 0.0;  // the James-Stein factor applied to the coefficients (0..1)
  std::array<double, kTerms> coefficients{};  // mm, after shrinkage
  std::array<double, kTerms * kTerms> covariance{};  // mm^2, row-major, after shrinkage
  // The same over blocks twice as wide (errors that correlate across the narrow blocks' borders); the narrow one's
  // where too few wide blocks hold points. Uncertainty takes the larger of the two at each phase.
  std::array<double, kTerms * kTerms> wide_covariance{};

  // The bias (mm) of a height at `phase` (its position between two images, a share of the step, -0.5..0.5) on a
  // level face, and its standard uncertainty (the larger of the two sandwiches'). 0 when not applied. The
  // uncertainty is that of the shrunk estimate about its mean; the share of the bias the shrinkage leaves in the
  // heights ((1 - shrinkage) times the bias, Stein's risk) is not added: u_z's blend (focus_variation.cc) keeps
  // (1 - shrinkage) of the model term, the bias's proxy, which on focusgen.py's level flats is 2.4-8 times that share.
  double At(double phase) const;
  double Uncertainty(double phase) const;
  // The bias's rms over the phase (mm); 0 when not applied.
  double Rms() const;
  // The share of the bias a height carries on a slope of `slope_mm_per_px`: 1 on a level face, falling to 0
  // (exp(-(slope / kFadeSlope)^2)); 0 when not applied.
  double Fade(double slope_mm_per_px) const;

  // When applied, the rms (mm) of the level points' departures from their local plane less the bias, over a box
  // of kScatterBoxPx around pixel (row, col): what the correction leaves there. NaN away from level points and
  // when not applied.
  double LevelScatter(int row, int col) const;
  int grid_stride = 1, grid_cols = 0;
  std::vector<float> level_scatter;  // mm, on the estimation grid (every grid_stride-th pixel)
};

// A height map (row-major, width x height; NaN where invalid) of a stack of images `step_mm` apart starting at
// `origin_mm`, and its slope (mm per px along x and y, from the smoothed heights).
struct PhaseBiasInput {
  int width = 0, height = 0;
  const std::vector<double>* z_mm = nullptr;
  const float* slope_x = nullptr;
  const float* slope_y = nullptr;
  double origin_mm = 0.0, step_mm = 0.0;
  // The heights (mm from origin_mm, row-major) a pixel's phase is read from: the map smoothed over its level
  // points (kPhaseSmoothingPx), so that a height's own error (0.1 step at NA 0.9 with a 0.8 um floor) does not
  // scatter its phase; a phase read from the noisy height itself dilutes the harmonics' regression towards zero
  // (errors in the regressor [Fuller 1987]). Null: the heights themselves.
  const float* phase_heights = nullptr;
  // The stack's largest departure from even steps (in steps): the phase is read against origin + k step, which
  // only an evenly stepped stack keeps (an uneven one is declined, see kUnevenSteps).
  double uneven_steps = 0.0;
  bool parallel = true;  // the correction in stripes of rows on OpenCV's thread pool
};

// The sigma (px) of the Gaussian that smooths the heights a phase is read from (PhaseBiasInput::phase_heights,
// filled by FocusAccumulator::Finish) and the slope (steps per px) over which its weights fade as the correction
// does (exp(-(slope / kPhaseSmoothingSlope)^2)), so that a calotte's rim beside a flat does not pull it.
inline constexpr double kPhaseSmoothingPx = 6.0;
inline constexpr double kPhaseSmoothingSlope = 0.1;

// The stack's phase bias, fitted on the map's level points.
PhaseBias EstimatePhaseBias(const PhaseBiasInput& in);

// The rms (steps) of the phase-locked bias the 5-point power fit leaves on a level face, predicted from the
// stack's own focus curve instead of measured: the curve P(u) = 1 + b |u| + c u^2 in the transformed measure P =
// (f / f_peak)^(-2/3) (u in steps from the surface; b the V-shaped top of a blur that grows linearly from its
// floor, c the round one), b and c such that its rises one and two images from the peak, median over the phase,
// are `rise1` and `rise2` (FocusCurveShape's medians over the stack's gentle peaks), run through PowerVertex
// (transform `power`) at kPredictionPhases phases between two images. Where EstimatePhaseBias declines (a flat
// about one period of the phase across, half its pixels invalid) this is the only measure of that bias: on
// focusgen.py it agrees with the measured bias where the correction applies (0.028-0.041 against 0.029-0.040
// step at NA 0.3-0.4 with 0.7-1 px textures). 0 when the rises do not describe a peak (rise2 <= rise1 or rise1 <= 0).
inline constexpr int kPredictionPhases = 64;
double PredictedPhaseBiasRms(double rise1, double rise2, double power);

// exp(-(slope / kFadeSlope)^2), the slope in steps per px: the share of the phase bias a height carries on a
// slope (its window's heights span phases and average it away).
double PhaseBiasFade(double slope_mm_per_px, double step_mm);

// Takes the bias, faded by the slope, off each finite height of in.z_mm (the same vector as `z_mm`, which is
// written); `u_mm` gets the correction's standard uncertainty per pixel (0 where nothing was taken off).
void CorrectPhaseBias(const PhaseBias& bias, const PhaseBiasInput& in, std::vector<double>& z_mm,
                      std::vector<float>& u_mm);

}  // namespace fvm::imaging
