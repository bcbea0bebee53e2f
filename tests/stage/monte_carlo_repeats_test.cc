// The machine Monte Carlo against repeat measurements of a machine it did not make (tests/stage/written_out_machine.h:
// [Aguado 2016] eq. 1 written out, cubics with ball-screw sines that no polynomial follows, the tracker's noise on its
// own coordinates). Each repeat reads the machine afresh, its identification readings and its validation readings,
// and is verified as fvm verify does; the Monte Carlo from one repeat alone must predict the mean and the spread of
// the repeats' validation mean errors ([GUM Supplement 1]: the prediction of what a repeat would show).

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <random>
#include <vector>

#include "stage/monte_carlo.h"
#include "stage/residual_field.h"
#include "tests/stage/written_out_machine.h"

namespace fvm::stage {
namespace {

using testing::Estimated;
using testing::MachineLayout;
using testing::MakeTruth;
using testing::Mesh;
using testing::Readings;
using testing::Tracker;
using testing::Truth;

// One repeat measurement: identification and validation readings with fresh noise, verified; its validation mean
// error as fvm verify --validate prints it.
struct Repeat {
  std::vector<Observation> readings, validation;
  VerificationResult verified;
  double validation_mean_um = 0;
};

Repeat Measure(const Truth& truth, const ParameterLayout& layout, const TrackerNoise& noise, unsigned seed) {
  const Tracker tracker;
  std::vector<Observation> readings = Readings(truth, Mesh({500, 300, 300}), tracker, &noise, seed);
  std::vector<Observation> validation = Readings(truth, Mesh({250, 250, 200}), tracker, &noise, seed + 7919);
  VerificationResult v = VerifyMachine(layout, readings, Estimated());
  const Calibration& c = v.identified.calibration;
  const double mean_um = Summarize(VolumetricResiduals(c.layout, &c.values, v.identified.pose, validation)).mean_um();
  return {std::move(readings), std::move(validation), std::move(v), mean_um};
}

// The independent check, rebuilt with more repeats: 180 readings of an order-2 model on a machine that
// leaves about 10 um rms to the model, an absolute distance meter's noise (about 20 um rms at 2-3 m), 539 validation
// readings. 40 repeats give the observed spread (sd) to 1 / sqrt(2 x 39) = 11 % and the observed mean to
// sd / sqrt(40), under 1 % here; 120 runs give the predicted spread to 6.5 %. The prediction depends on which repeat
// it starts from (that repeat's noise is in the estimate of the field): two starting repeats. Bounds: the issue's
// 0.8-1.25 for both ratios, about two standard errors of the spread ratio (13 %) either side. (The former truth, the
// model alone judged on the starting repeat's own validation readings, predicted the mean well here but the spread
// at 0.44-0.57 of the observed: the validation readings' noise was held, not drawn.)
TEST(MachineMonteCarlo, PredictsTheValidationErrorOfRepeatMeasurements) {
  const Truth truth = MakeTruth(11, false, 3.0);
  const ParameterLayout layout = MachineLayout(Basis::kLegendre, 2);
  const TrackerNoise noise = TrackerNoise::Preset("adm");
  constexpr int kRepeats = 40;
  std::vector<Repeat> repeats;
  std::vector<double> observed;
  for (int k = 0; k < kRepeats; ++k) {
    repeats.push_back(Measure(truth, layout, noise, 500 + static_cast<unsigned>(k)));
    observed.push_back(repeats.back().validation_mean_um);
  }
  const SampleSummary real = SummarizeSample(observed);
  for (int start : {0, 1}) {
    const Repeat& one = repeats[static_cast<size_t>(start)];
    MonteCarloOptions mc;
    mc.runs = 120;
    mc.seed = 3;
    const std::vector<MachineMonteCarloRun> runs =
        MachineMonteCarlo(layout, one.verified, one.readings, one.validation, noise, Estimated(), mc);
    std::vector<double> predicted;
    for (const MachineMonteCarloRun& r : runs) predicted.push_back(r.validation.mean_um());
    const SampleSummary simulated = SummarizeSample(predicted);
    std::printf("validation mean error: %d repeats %.2f +- %.2f um; Monte Carlo from repeat %d: %.2f +- %.2f um "
                "(ratios: mean %.3f, spread %.3f)\n",
                kRepeats, real.mean, real.sd, start, simulated.mean, simulated.sd, simulated.mean / real.mean,
                simulated.sd / real.sd);
    EXPECT_GT(simulated.mean / real.mean, 0.8) << "from repeat " << start;
    EXPECT_LT(simulated.mean / real.mean, 1.25) << "from repeat " << start;
    EXPECT_GT(simulated.sd / real.sd, 0.8) << "from repeat " << start;
    EXPECT_LT(simulated.sd / real.sd, 1.25) << "from repeat " << start;
  }
}

// Noise-free validation readings (what `fvm simulate tracker --validation` writes): their residuals are smaller than
// the tracker's noise, so the runs draw only the share of it that keeps their power (none here). The same 40
// repeats judged on the machine's exact readings; bounds as above.
TEST(MachineMonteCarlo, PredictsTheValidationErrorOnNoiseFreeValidationReadings) {
  const Truth truth = MakeTruth(11, false, 3.0);
  const ParameterLayout layout = MachineLayout(Basis::kLegendre, 2);
  const TrackerNoise noise = TrackerNoise::Preset("adm");
  const std::vector<Observation> exact = Readings(truth, Mesh({250, 250, 200}), Tracker{}, nullptr, 0);
  std::vector<double> observed;
  std::optional<Repeat> first;
  for (int k = 0; k < 40; ++k) {
    Repeat r = Measure(truth, layout, noise, 500 + static_cast<unsigned>(k));
    const Calibration& c = r.verified.identified.calibration;
    observed.push_back(Summarize(VolumetricResiduals(c.layout, &c.values, r.verified.identified.pose, exact)).mean_um());
    if (k == 0) first.emplace(std::move(r));
  }
  MonteCarloOptions mc;
  mc.runs = 120;
  mc.seed = 3;
  std::vector<double> predicted;
  for (const MachineMonteCarloRun& r : MachineMonteCarlo(layout, first->verified, first->readings, exact, noise, Estimated(), mc)) {
    predicted.push_back(r.validation.mean_um());
  }
  const SampleSummary real = SummarizeSample(observed), simulated = SummarizeSample(predicted);
  std::printf("noise-free validation: 40 repeats %.2f +- %.2f um; Monte Carlo %.2f +- %.2f um (ratios: mean %.3f, spread %.3f)\n",
              real.mean, real.sd, simulated.mean, simulated.sd, simulated.mean / real.mean, simulated.sd / real.sd);
  EXPECT_GT(simulated.mean / real.mean, 0.8);
  EXPECT_LT(simulated.mean / real.mean, 1.25);
  EXPECT_GT(simulated.sd / real.sd, 0.8);
  EXPECT_LT(simulated.sd / real.sd, 1.25);
}

// Readings that carry their own covariances (multilaterated points: a few um, far below the tracker's tens at
// 2-3 m): the runs draw each reading's noise from its covariance. 24 repeats drawn here with those covariances
// scatter their predictions by what the Monte Carlo from one of them predicts (the sd of a pooled 3D sd from 24
// repeats: about 15 %, from 40 runs 11 %: within 25 %), while the tracker's model would predict several times more.
TEST(MachineMonteCarlo, DrawsReadingsThatCarryTheirOwnCovarianceFromIt) {
  const Truth truth = MakeTruth(12, false, 3.0);
  const ParameterLayout layout = MachineLayout(Basis::kLegendre, 2);
  const TrackerNoise tracker_model = TrackerNoise::Preset("published");
  const std::vector<Observation> exact = Readings(truth, Mesh({500, 300, 300}), Tracker{}, nullptr, 0);
  const std::vector<Observation> evaluation = Readings(truth, Mesh({500, 500, 400}), Tracker{}, nullptr, 0);
  // Each point's covariance: anisotropic, 2-6 um, turned with the point's index.
  std::vector<Eigen::Matrix3d> covariances;
  for (size_t i = 0; i < exact.size(); ++i) {
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.1 * static_cast<double>(i), Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    covariances.push_back(turn * Eigen::Vector3d(4e-6, 1e-5, 3.6e-5).asDiagonal() * turn.transpose());
  }
  const auto draw = [&](unsigned seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<Observation> out = exact;
    for (size_t i = 0; i < out.size(); ++i) {
      const Eigen::Matrix3d l = covariances[i].llt().matrixL();
      out[i].measured += l * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
      out[i].covariance = covariances[i];
    }
    return out;
  };
  constexpr int kReal = 24;
  std::vector<std::vector<Eigen::Vector3d>> predictions;
  std::vector<Observation> first_readings;
  std::optional<VerificationResult> first;
  for (int k = 0; k < kReal; ++k) {
    const std::vector<Observation> readings = draw(900 + static_cast<unsigned>(k));
    VerificationResult v = VerifyMachine(layout, readings, Estimated());
    const Calibration& c = v.identified.calibration;
    predictions.push_back(PredictedReadings(c.layout, &c.values, v.identified.pose, evaluation));
    if (k == 0) first.emplace(std::move(v)), first_readings = readings;
  }
  MonteCarloOptions mc;
  mc.runs = 40;
  mc.seed = 5;
  mc.readings_carry_covariances = true;
  const std::vector<PointSpread> own =
      PointSpreads(MachineMonteCarlo(layout, *first, first_readings, evaluation, tracker_model, Estimated(), mc));
  mc.readings_carry_covariances = false;
  const std::vector<PointSpread> modelled =
      PointSpreads(MachineMonteCarlo(layout, *first, first_readings, evaluation, tracker_model, Estimated(), mc));
  double real_sum = 0, own_sum = 0, modelled_sum = 0;
  const size_t offset = first_readings.size();
  for (size_t p = 0; p < evaluation.size(); ++p) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& pr : predictions) mean += pr[p];
    mean /= kReal;
    for (const auto& pr : predictions) real_sum += (pr[p] - mean).squaredNorm() / (kReal - 1);
    own_sum += own[offset + p].covariance.trace();
    modelled_sum += modelled[offset + p].covariance.trace();
  }
  const double real_sd = std::sqrt(real_sum), own_sd = std::sqrt(own_sum), modelled_sd = std::sqrt(modelled_sum);
  std::printf("prediction spread (3D sd, rms): %d repeats %.2f um, Monte Carlo with the readings' covariances %.2f um, "
              "with the tracker model %.2f um\n",
              kReal, 1e3 * real_sd / std::sqrt(evaluation.size()), 1e3 * own_sd / std::sqrt(evaluation.size()),
              1e3 * modelled_sd / std::sqrt(evaluation.size()));
  EXPECT_NEAR(own_sd / real_sd, 1.0, 0.25);
  EXPECT_GT(modelled_sd / real_sd, 2.0);
}

// The field: the power above the known covariances, per coordinate, spread alike over the directions; a component
// along a noiseless direction is kept whole, one along a noisy direction scaled by sqrt(s^2 / (s^2 + l)).
TEST(ResidualField, KeepsThePowerAboveTheNoiseAlikeInEveryDirection) {
  const std::vector<Eigen::Vector3d> residuals{Eigen::Vector3d(1, 0, 4), Eigen::Vector3d(0, 1, 4)};
  const std::vector<Eigen::Matrix3d> noisy_z(2, Eigen::Vector3d(0, 0, 8).asDiagonal());
  const ResidualField field = ShrunkResidualField(residuals, noisy_z);  // (2 + 32 - 16) / 6 = 3 per coordinate
  EXPECT_DOUBLE_EQ(field.sigma_mm, std::sqrt(3.0));
  EXPECT_NEAR(field.offsets_mm[0].x(), 1.0, 1e-12);
  EXPECT_NEAR(field.offsets_mm[0].y(), 0.0, 1e-12);
  EXPECT_NEAR(field.offsets_mm[0].z(), 4.0 * std::sqrt(3.0 / 11.0), 1e-12);
  // Residuals no larger than their noise: no field.
  const std::vector<Eigen::Matrix3d> large(2, 20.0 * Eigen::Matrix3d::Identity());
  EXPECT_EQ(ShrunkResidualField(residuals, large).offsets_mm[1], Eigen::Vector3d::Zero());
  const std::vector<Eigen::Matrix3d> one(1, Eigen::Matrix3d::Identity());
  EXPECT_THROW(ShrunkResidualField(residuals, one), std::invalid_argument);
}

// Held-out residuals along one direction of the estimation error (variance l): a component no larger than that
// error is taken out whole; one far above it keeps its power less the error's, sqrt(a^2 - l); the rest is the field,
// kept whole where the readings are noise-free.
TEST(ResidualField, HeldOutTakesOutTheEstimationErrorAndKeepsTheFieldAlongIt) {
  const double s = 0.002;  // mm: the estimation error's standard deviation along its one direction w
  std::vector<Eigen::Vector3d> w(4, Eigen::Vector3d(0.5, 0, 0)), u;  // |w| = 1 over the four points
  for (int p = 0; p < 4; ++p) u.emplace_back(0, p % 2 == 0 ? 0.01 : -0.01, 0.004 * p);  // orthogonal to w
  std::vector<std::vector<Eigen::Vector3d>> runs;
  for (double t : {-s, 0.0, s}) {  // variance along w: (s^2 + s^2) / 2
    std::vector<Eigen::Vector3d> run;
    for (const Eigen::Vector3d& v : w) run.push_back(t * v);
    runs.push_back(run);
  }
  const std::vector<Eigen::Matrix3d> noise_free(4, Eigen::Matrix3d::Zero());
  for (double along : {0.5 * s, 10 * s}) {
    std::vector<Eigen::Vector3d> residuals;
    for (int p = 0; p < 4; ++p) residuals.push_back(u[static_cast<size_t>(p)] + along * w[static_cast<size_t>(p)]);
    const ResidualField field = HeldOutResidualField(residuals, noise_free, runs, 3);
    const double kept = along > s ? std::sqrt(along * along - s * s) : 0.0;
    for (int p = 0; p < 4; ++p) {
      const Eigen::Vector3d expected = u[static_cast<size_t>(p)] + kept * w[static_cast<size_t>(p)];
      EXPECT_NEAR((field.offsets_mm[static_cast<size_t>(p)] - expected).norm(), 0.0, 1e-12) << "along " << along << ", point " << p;
    }
  }
  EXPECT_THROW(HeldOutResidualField(std::vector<Eigen::Vector3d>(3), noise_free, runs, 3), std::invalid_argument);
}

// The field's power in the estimation error's span is one for all its directions: one direction of large estimation
// error (sd 10 s) where the reference's error happens to be 2 sd (20 s), eight of small error (sd s) with components
// of s, all of it estimation error. Judged alone, the large component would keep sqrt(400 - 100) / 20 = 87 % of
// itself; pooled, the eight say that the field is weak there (f = 0.59 s^2 from sum a_j^2 / (f + l_j) = 9), and it
// keeps sqrt(f / (f + 100 s^2)) = 7.7 %. The field outside the span stays whole.
TEST(ResidualField, HeldOutLearnsTheFieldsPowerFromEveryDirectionOfTheEstimationError) {
  const double s = 0.001;
  constexpr int kPoints = 9;
  const std::vector<double> sd{10 * s, s, s, s, s, s, s, s, s}, along{20 * s, s, s, s, s, s, s, s, s};
  // Direction j: the x coordinate of point j alone. Runs +-c_j along it: variance 2 c_j^2 / (runs - 1) = sd_j^2.
  std::vector<std::vector<Eigen::Vector3d>> runs;
  const double runs_minus_one = 2.0 * kPoints - 1.0;
  for (int j = 0; j < kPoints; ++j) {
    for (double sign : {-1.0, 1.0}) {
      std::vector<Eigen::Vector3d> run(kPoints, Eigen::Vector3d::Zero());
      run[static_cast<size_t>(j)].x() = sign * sd[static_cast<size_t>(j)] * std::sqrt(runs_minus_one / 2.0);
      runs.push_back(run);
    }
  }
  std::vector<Eigen::Vector3d> residuals, outside;
  for (int p = 0; p < kPoints; ++p) {
    outside.emplace_back(0.0, 0.02 * (p % 3 - 1), 0.01 * (p + 1));
    residuals.push_back(outside.back() + Eigen::Vector3d(along[static_cast<size_t>(p)], 0, 0));
  }
  const std::vector<Eigen::Matrix3d> noise_free(kPoints, Eigen::Matrix3d::Zero());
  const ResidualField field = HeldOutResidualField(residuals, noise_free, runs, kPoints);
  std::vector<double> keep;
  for (int p = 0; p < kPoints; ++p) {
    const Eigen::Vector3d f = field.offsets_mm[static_cast<size_t>(p)];
    EXPECT_NEAR((Eigen::Vector3d(0, f.y(), f.z()) - outside[static_cast<size_t>(p)]).norm(), 0.0, 1e-12) << "point " << p;
    keep.push_back(f.x() / along[static_cast<size_t>(p)]);
  }
  EXPECT_NEAR(keep[0], 0.0767, 0.0005);
  // The power behind the kept shares, f = l keep^2 / (1 - keep^2), is one, and it solves the moment equation.
  const double power = 100 * s * s * keep[0] * keep[0] / (1 - keep[0] * keep[0]);
  double moment = 0;
  for (int p = 0; p < kPoints; ++p) {
    const double l = sd[static_cast<size_t>(p)] * sd[static_cast<size_t>(p)];
    EXPECT_NEAR(l * keep[static_cast<size_t>(p)] * keep[static_cast<size_t>(p)] / (1 - keep[static_cast<size_t>(p)] * keep[static_cast<size_t>(p)]), power, 1e-9 * power);
    moment += along[static_cast<size_t>(p)] * along[static_cast<size_t>(p)] / (power + l);
  }
  EXPECT_NEAR(moment, kPoints, 1e-6);
}

}  // namespace
}  // namespace fvm::stage
