#pragma once
// The part of a machine its identified model cannot follow, as a Monte Carlo's truth carries it. A truth that is the
// model alone leaves that part out of every predicted residual; a truth that keeps the readings' residuals whole and
// draws fresh noise on top counts the noise twice (and, on held-out readings, the model's own estimation error too).
//
// A residual (reading - model) is r_i = u_i + e_i: the unfollowed part u and a part e of known covariance C_i (on
// fitted readings the share of their noise the fit did not take, on held-out readings their noise plus the model's
// estimation error). The field's power per coordinate is estimated by moments, s_u^2 = max(0, sum(|r_i|^2 - tr C_i)
// / 3n), taken alike in every direction (a machine's error has no preference for the tracker's axes, while a
// tracker's noise is far larger across the beam than along it). Each residual's component along a principal axis
// of C_i (variance l) is then scaled by sqrt(s_u^2 / (s_u^2 + l)): the square root of a Wiener filter's gain, so
// that the component keeps the field's expected power s_u^2, and fresh noise drawn on top of the field gives
// residuals of the observed power on average.

#include <Eigen/Core>
#include <vector>

namespace fvm::stage {

struct ResidualField {
  std::vector<Eigen::Vector3d> offsets_mm;  // the field at each reading
  double sigma_mm = 0;                      // s_u: its standard deviation per coordinate
};

// `residuals_mm`: reading - model; `covariances`: of each residual's part that is not the field (mm^2, positive
// semi-definite). Throws std::invalid_argument when the two vectors differ in size.
ResidualField ShrunkResidualField(const std::vector<Eigen::Vector3d>& residuals_mm,
                                  const std::vector<Eigen::Matrix3d>& covariances);

// The field at held-out readings (validation readings, never fitted). Their residual is r = u + d + n: the field u,
// the reference model's own estimation error d and the readings' noise n (covariance N_p; zero for noise-free
// readings). d is no per-point noise: it is the error of the model's few coefficients and pose, smooth and
// correlated over every point, and a field that keeps it gives each run's error a share along the reference's own
// that no repeat has: the runs' validation mean errors then scatter wider, and the more so the luckier or unluckier
// the reference's readings were. d's covariance is the runs' (`estimation_errors_mm`: each run's deviation at every
// point). Along each of its leading `dimension` principal directions (variance l_j, the readings' noise there n_j)
// the residual's component is a_j ~ N(0, f + l_j + n_j), with f the field's power per direction. A smooth field
// puts far more of its power in the model's few directions than in the rest (trackergen's machines: 500-1600 um^2
// there, 30-40 elsewhere), so f is estimated there, one for all of them, by Paule and Mandel's moment equation
// sum a_j^2 / (f + l_j + n_j) = m [Paule 1982] (the empirical Bayes of [Efron 1975] with unequal variances), and
// each component is scaled by sqrt((f + n_j) / (f + n_j + l_j)) so that it keeps the expected power of the field and
// the noise. One power for all directions is what makes the estimate stable: from each component alone
// (f_j = a_j^2 - l_j - n_j) a chance estimation error of two standard deviations would keep three quarters of
// itself, and the predicted spread of the validation mean error followed the reference's luck (0.86-1.36 of 200
// repeats' over 12 starting repeats of trackergen's machines 4-6; 0.85-1.10 pooled). The rest is then shrunk for
// the readings' noise as ShrunkResidualField does, with the field's power per coordinate by moments,
// (sum |r|^2 - tr N - tr Cov d) / 3n. Throws std::invalid_argument when the sizes differ.
ResidualField HeldOutResidualField(const std::vector<Eigen::Vector3d>& residuals_mm,
                                   const std::vector<Eigen::Matrix3d>& noise_covariances,
                                   const std::vector<std::vector<Eigen::Vector3d>>& estimation_errors_mm, int dimension);

}  // namespace fvm::stage
