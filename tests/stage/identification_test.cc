// Identification of the published models ([Pérez 2019]) on measurements made with an independent forward model: the
// published equation written out in tests/stage/published_model.h, not the library's chain, inverse or first tile, so
// that a mistake shared by simulator and identification cannot cancel. The truth carries a 37 mm ripple of 0.3 um on
// every translation on top of straight lines: no polynomial model takes it exactly.

#include "stage/identification.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <map>
#include <optional>
#include <random>

#include "stage/fvm_stage_models.h"
#include "stage/undetermined_spread.h"
#include "stage/validation.h"
#include "tests/stage/published_model.h"

namespace fvm::stage {
namespace {

// The ripple on every translation: well below the noise per centre, but a shape the models cannot take.
constexpr double kRippleMm = 0.3e-3;

using Experiment = testing::PublishedMeasurements;

Experiment Simulate(unsigned seed, double noise_um = 0.5, bool same_start = true, double ripple_mm = kRippleMm) {
  return testing::MeasureOnPublishedStage(testing::PublishedStage::Draw(seed, ripple_mm), seed, noise_um * 1e-3,
                                          /*validation=*/10, /*apart=*/!same_start);
}

IdentificationOptions AnchorOptions(const stage::MeasurementSet& set, Anchor anchor) {
  IdentificationOptions o;
  o.anchor = anchor;
  o.anchors = set.anchors;
  return o;
}

double ValidationMean(const IdentificationResult& r, const Experiment& e) {
  return Validate(&r.calibration, e.validate.observations, e.validate.anchors).mean_mm;
}

TEST(Identification, OrdersOneAndTwoConvergeAndBeatTheSimplifiedModel) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Experiment e = Simulate(seed);
    const double mean9 = ValidationMean(Identify(FvmModelLayout("9"), e.identify.observations), e);
    for (const char* model : {"27", "42"}) {
      const IdentificationResult r = Identify(FvmModelLayout(model), e.identify.observations);
      EXPECT_TRUE(r.converged) << model << " seed " << seed << ": " << r.solver_report;
      // The truth is first order, so the simplified model cannot follow it; 27 and 42 must not do worse.
      EXPECT_LT(ValidationMean(r, e), mean9) << model << " seed " << seed;
      // Noise is 0.5 um per coordinate in both measurements: a perfect model leaves sqrt(3 * 2) * 0.5 = 1.22 um
      // rms, the ripple 0.3 um / sqrt(2) per translation term it rides on (at most ~0.4 um rms added in
      // quadrature over the coordinates: 1.28 um); allow the parameter uncertainty on top. A model that got the
      // published equation wrong (a sign, a transposed rotation) leaves tens of um here.
      EXPECT_LT(r.residual_summary.rms_mm, 1.6e-3) << model;
      EXPECT_GT(r.residual_summary.rms_mm, 0.9e-3) << model;  // fewer than 51 x 3 - 27 degrees of freedom cannot explain less
    }
  }
}

// An independent estimator of the same model on the same information: Gauss-Newton with central-difference
// Jacobians over every coefficient, minimum-norm steps (complete orthogonal decomposition) for the rank deficiency.
std::vector<double> IndependentLeastSquares(const ParameterLayout& layout, const std::vector<Observation>& obs) {
  std::vector<double> x(static_cast<size_t>(layout.NumFree()), 0.0);
  const Eigen::VectorXd tau = PlausibleSizes(layout);
  for (int iteration = 0; iteration < 6; ++iteration) {
    Eigen::MatrixXd j(3 * obs.size(), layout.NumFree());
    Eigen::VectorXd r(3 * obs.size());
    for (size_t i = 0; i < obs.size(); ++i) {
      r.segment<3>(3 * static_cast<Eigen::Index>(i)) = Forward(layout, x, obs[i].command) - obs[i].measured;
      for (int c = 0; c < layout.NumFree(); ++c) {
        std::vector<double> up = x, down = x;
        const double h = 1e-4 * tau[c];
        up[static_cast<size_t>(c)] += h;
        down[static_cast<size_t>(c)] -= h;
        j.block<3, 1>(3 * static_cast<Eigen::Index>(i), c) = (Forward(layout, up, obs[i].command) - Forward(layout, down, obs[i].command)) / (2 * h);
      }
    }
    const Eigen::MatrixXd js = j * tau.asDiagonal();
    const Eigen::VectorXd step = tau.asDiagonal() * js.completeOrthogonalDecomposition().solve(-r);
    for (int c = 0; c < layout.NumFree(); ++c) x[static_cast<size_t>(c)] += step[c];
  }
  return x;
}

TEST(Identification, ValidationWithinTenPercentOfAnIndependentLeastSquaresFit) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Experiment e = Simulate(seed);
    for (const char* model : {"27", "42"}) {
      const ParameterLayout layout = FvmModelLayout(model);
      const std::vector<double> ls = IndependentLeastSquares(layout, e.identify.observations);
      const Calibration reference{"ls", layout, ls, {}, 0.0, std::nullopt, {}};
      const double ls_mean = Validate(&reference, e.validate.observations, e.validate.anchors).mean_mm;
      const double ours = ValidationMean(Identify(layout, e.identify.observations), e);
      EXPECT_LT(ours, 1.1 * ls_mean) << model << " seed " << seed << ": ours " << ours * 1e3 << " um, least squares "
                                     << ls_mean * 1e3 << " um";
    }
  }
}

TEST(Identification, EstimatesLieWithinThreeUncertaintiesOfTheEstimableTruth) {
  // Coefficients the data cannot tell apart are not estimable one by one; what the data determine is the truth
  // projected onto the identified layout: the same layout fitted to the noise-free measurements.
  for (unsigned seed : {1u, 2u, 3u}) {
    const Experiment noisy = Simulate(seed);
    const Experiment clean = Simulate(seed, 0.0);
    const IdentificationResult r = Identify(FvmModelLayout("27"), noisy.identify.observations);
    const IdentificationResult truth = Identify(r.calibration.layout, clean.identify.observations);
    ASSERT_TRUE(truth.fixed.empty());
    const Eigen::VectorXd u = r.calibration.StandardUncertainty();
    for (int i = 0; i < r.calibration.layout.NumFree(); ++i) {
      const double z = (r.calibration.values[static_cast<size_t>(i)] - truth.calibration.values[static_cast<size_t>(i)]) / u[i];
      EXPECT_LT(std::abs(z), 3.0) << r.calibration.layout.FreeNames()[static_cast<size_t>(i)] << " seed " << seed;
    }
  }
}

// What the covariance and noise predict for the validation rms, against what independent measurements show: the
// published stage, measured through the equation written out, with and without the ripple. One batch draws its
// coefficients' error once, a vector of 15 whose rms over the validation placements scatters like a chi-square of a
// few degrees of freedom: seeds 1-3 alone show observed / predicted 1.37, 0.91, 1.38 (no ripple) and 1.51, 1.04, 1.42
// (ripple) although noise-free batches leave 0.01 um (no ripple): the prediction is an expectation, and what tests it
// is the pooled rms over independent batches (20: the pooled ratio moves by about 5 % from 10 batches to 40).
// Measured over 40: 1.03 without the ripple, 1.10 with it (the ripple's share the model takes up, 0.8 um, is in
// neither the noise nor the covariance). The coefficients fixed as undetermined are not the excess: with the free
// coefficients' absorption, their plausible spread (undetermined_spread.h) adds 0.04-0.19 um here.
TEST(Identification, PredictedValidationErrorMatchesObserved) {
  for (double ripple : {0.0, kRippleMm}) {
    double observed_sq = 0, predicted_sq = 0;
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const Experiment e = Simulate(seed, 0.5, true, ripple);
      const IdentificationResult r = Identify(FvmModelLayout("27"), e.identify.observations);
      const ValidationStats v = Validate(&r.calibration, e.validate.observations, e.validate.anchors);
      observed_sq += v.rms_mm * v.rms_mm;
      predicted_sq += v.predicted_rms_mm * v.predicted_rms_mm;
      // One batch: within the scatter of a single draw of the coefficients' error.
      EXPECT_GT(v.rms_mm / v.predicted_rms_mm, 0.7) << "seed " << seed << " ripple " << ripple;
      EXPECT_LT(v.rms_mm / v.predicted_rms_mm, 1.7) << "seed " << seed << " ripple " << ripple;
    }
    const double ratio = std::sqrt(observed_sq / predicted_sq);
    EXPECT_GT(ratio, 0.8) << "ripple " << ripple;
    EXPECT_LT(ratio, 1.25) << "ripple " << ripple;
  }
}

// The undetermined coefficients' share of the prediction against draws written here: the fixed coefficients drawn
// from their prior, their effect on the identification centres refitted by the free ones (linear least squares on
// central-difference columns of the forward model), and what is left on the validation placements in their first
// tiles' frames. 400 draws give the rms to about 5 %.
TEST(Identification, UndeterminedShareIsWhatDrawsOfTheFixedCoefficientsLeaveAfterRefitting) {
  const Experiment e = Simulate(3);
  const IdentificationResult r = Identify(FvmModelLayout("27"), e.identify.observations);
  const std::optional<Calibration> spread = UndeterminedSpread(r.calibration);
  ASSERT_TRUE(spread.has_value());
  const double undetermined = UndeterminedRms(r.calibration, e.validate.observations, e.validate.anchors);
  ASSERT_GT(undetermined, 0.0);
  const ParameterLayout& freed = spread->layout;
  const auto columns = [&](const Eigen::Vector3d& q) {
    Eigen::MatrixXd j(3, freed.NumFree());
    for (int c = 0; c < freed.NumFree(); ++c) {
      std::vector<double> up = spread->values, down = spread->values;
      up[static_cast<size_t>(c)] += 1e-6;
      down[static_cast<size_t>(c)] -= 1e-6;
      j.col(c) = (Forward(freed, up, q) - Forward(freed, down, q)) / 2e-6;
    }
    return j;
  };
  std::vector<int> free_slots, fixed_slots;
  for (const std::string& name : r.calibration.layout.FreeNames()) free_slots.push_back(freed.FreeIndexOf(name));
  for (const std::string& name : r.calibration.undetermined.names) fixed_slots.push_back(freed.FreeIndexOf(name));
  const auto pick = [](const Eigen::MatrixXd& j, const std::vector<int>& slots) {
    Eigen::MatrixXd out(j.rows(), static_cast<Eigen::Index>(slots.size()));
    for (size_t k = 0; k < slots.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = j.col(slots[k]);
    return out;
  };
  Eigen::MatrixXd id(3 * e.identify.observations.size(), freed.NumFree()), val(3 * e.validate.observations.size(), freed.NumFree());
  for (size_t i = 0; i < e.identify.observations.size(); ++i) id.middleRows(3 * static_cast<Eigen::Index>(i), 3) = columns(e.identify.observations[i].command);
  for (size_t i = 0; i < e.validate.observations.size(); ++i) {
    const Observation& o = e.validate.observations[i];
    val.middleRows(3 * static_cast<Eigen::Index>(i), 3) = columns(o.command) - columns(e.validate.anchors[static_cast<size_t>(o.group)]);
  }
  const Eigen::MatrixXd id_free = pick(id, free_slots), id_fixed = pick(id, fixed_slots);
  const Eigen::MatrixXd val_free = pick(val, free_slots), val_fixed = pick(val, fixed_slots);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> refit(id_free);
  const Eigen::VectorXd prior = UndeterminedPrior(r.calibration);
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  double sum = 0;
  constexpr int kDraws = 400;
  for (int d = 0; d < kDraws; ++d) {
    Eigen::VectorXd delta(prior.size());
    for (Eigen::Index k = 0; k < prior.size(); ++k) delta[k] = std::sqrt(prior[k]) * normal(random);
    const Eigen::VectorXd taken = refit.solve(Eigen::VectorXd(id_fixed * delta));
    sum += (val_free * taken - val_fixed * delta).squaredNorm() / static_cast<double>(e.validate.observations.size());
  }
  const double drawn = std::sqrt(sum / kDraws);
  EXPECT_NEAR(undetermined, drawn, 0.15 * drawn) << "drawn " << drawn * 1e3 << " um";
}

TEST(Identification, AnchoringAtTheFirstTileHandlesPlacementsThatStartApart) {
  const Experiment e = Simulate(4, 0.5, /*same_start=*/false);
  const IdentificationResult plain = Identify(FvmModelLayout("27"), e.identify.observations);
  const IdentificationResult anchored =
      Identify(FvmModelLayout("27"), e.identify.observations, AnchorOptions(e.identify, Anchor::kFirstTile));
  EXPECT_LT(ValidationMean(anchored, e), 2e-3);
  EXPECT_GT(ValidationMean(plain, e), 2 * ValidationMean(anchored, e));
  // Offsets cancel when every measurement is referenced to its own first tile: they are named, not solved for.
  std::vector<std::string> fixed;
  for (const FixedCoefficient& f : anchored.fixed) fixed.push_back(f.name);
  EXPECT_THAT(fixed, ::testing::IsSupersetOf({"xTx0", "xTy0", "xTz0"}));
}

TEST(Identification, NamesTheCoefficientsItCannotDetermine) {
  const Experiment e = Simulate(1);
  const IdentificationResult r = Identify(FvmModelLayout("27"), e.identify.observations);
  std::map<std::string, std::string> reasons;
  for (const FixedCoefficient& f : r.fixed) reasons[f.name] = f.reason;
  EXPECT_EQ(reasons["yTx0"], "same effect as 1 * xTx0 on these data");
  EXPECT_THAT(reasons["xRy0"], ::testing::HasSubstr("pitch and roll need height changes"));
  EXPECT_EQ(r.calibration.layout.FindCoefficient("xTy1"), -1);  // not part of the 27 model at all
  EXPECT_EQ(r.calibration.layout.NumFree() + static_cast<int>(r.fixed.size()), 27);
}

TEST(Identification, TooFewCentresForTheModelIsAClearError) {
  const Experiment e = Simulate(1);
  const std::vector<Observation> few(e.identify.observations.begin(), e.identify.observations.begin() + 10);
  EXPECT_THAT([&] { Identify(FvmModelLayout("42"), few); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("fewer than the 42 coefficients")));
}

TEST(Identification, RobustLossResistsAFailedSphereFit) {
  Experiment e = Simulate(2);
  e.identify.observations[20].command += Eigen::Vector3d(0.05, -0.03, 0.02);  // a 60 um blunder
  const double clean = ValidationMean(Identify(FvmModelLayout("27"), Simulate(2).identify.observations), e);
  const double plain = ValidationMean(Identify(FvmModelLayout("27"), e.identify.observations), e);
  IdentificationOptions robust;
  robust.loss = "cauchy";
  robust.loss_scale_mm = 0.002;
  const double cauchy = ValidationMean(Identify(FvmModelLayout("27"), e.identify.observations, robust), e);
  EXPECT_GT(plain, 1.5 * clean);
  EXPECT_LT(cauchy, 1.15 * clean);
}

}  // namespace
}  // namespace fvm::stage
