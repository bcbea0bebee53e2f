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
// that no repeat has (the runs' validation mean errors then scatter up to 1.5x wider than 200 repeats of
// trackergen's machines do). d's covariance is the runs' (`estimation_errors_mm`: each run's
// deviation at every point): along each of its leading `dimension` principal directions (variance l_i), the
// residual's component a_i is reduced by its expected share of estimation error, l_i / (l_i + f_i + n_i), with the
// field's power there f_i = max(0, a_i^2 - l_i - n_i) estimated from that component alone (positive-part shrinkage,
// empirical Bayes [Efron 1973]): a component no larger than the estimation error is taken out whole, a component
// of the field far above it is kept. A smooth field has a share of its power in the model's directions, so a
// shrinkage with one power for every direction would take the field out there too (and predict too narrow a
// spread). The rest is then shrunk for the readings' noise as ShrunkResidualField does, with the field's power per
// coordinate by moments, (sum |r|^2 - tr N - tr Cov d) / 3n. Throws std::invalid_argument when the sizes differ.
ResidualField HeldOutResidualField(const std::vector<Eigen::Vector3d>& residuals_mm,
                                   const std::vector<Eigen::Matrix3d>& noise_covariances,
                                   const std::vector<std::vector<Eigen::Vector3d>>& estimation_errors_mm, int dimension);

}  // namespace fvm::stage
