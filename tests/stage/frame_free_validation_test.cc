// Judging a calibration by what no frame changes (stage/validation.h), on independent data whose stitched exports
// turn with the stage at their first tile ([Pérez 2019] eq. 1 written out in published_model.h): the rigid fit per
// placement against a rigid fit written here, and each figure against its prediction.

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <map>

#include "stage/fvm_stage_models.h"
#include "stage/identification.h"
#include "stage/validation.h"
#include "tests/stage/published_model.h"

namespace fvm::stage {
namespace {

// [Kabsch 1976]: the rotation and translation that take p onto s in least squares, and the rms of what is left.
double IndependentRigidRms(const std::vector<Eigen::Vector3d>& p, const std::vector<Eigen::Vector3d>& s, double* sum_sq) {
  Eigen::Vector3d cp = Eigen::Vector3d::Zero(), cs = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < p.size(); ++i) cp += p[i], cs += s[i];
  cp /= static_cast<double>(p.size());
  cs /= static_cast<double>(s.size());
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < p.size(); ++i) h += (p[i] - cp) * (s[i] - cs).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  double sq = 0;
  for (size_t i = 0; i < p.size(); ++i) sq += (r * (p[i] - cp) + cs - s[i]).squaredNorm();
  *sum_sq += sq;
  return std::sqrt(sq / static_cast<double>(p.size()));
}

struct Turned {
  testing::PublishedStage stage;
  testing::PublishedMeasurements m;
  IdentificationResult fit;
};

// The published procedure (placements sharing a start, no anchoring) on a first-order stage whose guideways turn
// by tens of microradians, 0.5 um noise per coordinate, exports that turn at their first tiles.
Turned Calibrate(unsigned seed) {
  const testing::PublishedStage stage = testing::PublishedStage::Draw(seed, 0.0, 3e-5);
  testing::PublishedMeasurements m = testing::MeasureOnPublishedStage(stage, seed, 5e-4, 10, false, /*turned=*/true);
  IdentificationOptions options;
  options.anchors = m.identify.anchors;
  IdentificationResult fit = Identify(FvmModelLayout("27"), m.identify.observations, options);
  return {stage, std::move(m), std::move(fit)};
}

TEST(FrameFreeValidation, RigidFigureIsAnIndependentRigidFitAndItsPredictionHolds) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Turned t = Calibrate(seed);
    const FrameFreeStats rigid = RigidValidation(&t.fit.calibration, t.m.validate.observations);
    std::map<int, std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>> by_group;
    for (const Observation& o : t.m.validate.observations) {
      by_group[o.group].first.push_back(Correct(t.fit.calibration, o.command).position);
      by_group[o.group].second.push_back(o.measured);
    }
    double sum_sq = 0;
    for (const auto& [group, ps] : by_group) IndependentRigidRms(ps.first, ps.second, &sum_sq);
    const double independent = std::sqrt(sum_sq / static_cast<double>(t.m.validate.observations.size()));
    EXPECT_NEAR(rigid.rms_mm, independent, 0.1 * independent) << "seed " << seed;  // the 10 %
    // What the covariance and the noise predict: 0.8-1.3 of what is observed (the target).
    EXPECT_GT(rigid.predicted_rms_mm, 0.8 * rigid.rms_mm) << "seed " << seed;
    EXPECT_LT(rigid.predicted_rms_mm, 1.3 * rigid.rms_mm) << "seed " << seed;
    const FrameFreeStats distances = PairDistanceValidation(&t.fit.calibration, t.m.validate.observations);
    EXPECT_EQ(distances.count, 10 * 17 * 16 / 2);
    EXPECT_GT(distances.predicted_rms_mm, 0.8 * distances.rms_mm) << "seed " << seed;
    EXPECT_LT(distances.predicted_rms_mm, 1.3 * distances.rms_mm) << "seed " << seed;
  }
}

TEST(FrameFreeValidation, FirstTilePredictionCoversTheTurn) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Turned t = Calibrate(seed);
    const ValidationStats rotated =
        Validate(&t.fit.calibration, t.m.validate.observations, t.m.validate.anchors, StitchedFrame::kRotated);
    EXPECT_EQ(rotated.turn, "model");
    EXPECT_GE(rotated.predicted_rms_mm, 0.8 * rotated.rms_mm) << "seed " << seed;
    // Left out, the turn is what the prediction does not cover: the first-tile figure grows past it.
    const ValidationStats translated =
        Validate(&t.fit.calibration, t.m.validate.observations, t.m.validate.anchors, StitchedFrame::kTranslated);
    EXPECT_GT(translated.rms_mm, rotated.rms_mm) << "seed " << seed;
  }
}

// The 27 model with constant rotations only: it follows the positions, but not the turn from one first tile to
// another, which its prediction must then carry.
TEST(FrameFreeValidation, AModelWithoutTurnTermsCarriesTheTurnInItsPrediction) {
  ParameterLayout layout = FvmModelLayout("27");
  for (const char* r : {"xRx", "xRy", "xRz", "yRx", "yRy", "yRz"}) layout.SetTerm(r, Basis::kPower, 0);
  ASSERT_TRUE(TurnCoefficients(layout).empty());
  for (unsigned seed : {1u, 2u, 3u}) {
    const testing::PublishedStage stage = testing::PublishedStage::Draw(seed, 0.0, 3e-5);
    const testing::PublishedMeasurements m = testing::MeasureOnPublishedStage(stage, seed, 5e-4, 10, false, true);
    IdentificationOptions options;
    options.anchors = m.identify.anchors;
    const IdentificationResult fit = Identify(layout, m.identify.observations, options);
    const ValidationStats v = Validate(&fit.calibration, m.validate.observations, m.validate.anchors, StitchedFrame::kRotated);
    EXPECT_EQ(v.turn, "uncertainty");
    EXPECT_GT(v.turn_u_rad.z(), 0.0);
    EXPECT_GE(v.predicted_rms_mm, 0.8 * v.rms_mm) << "seed " << seed;
  }
}

}  // namespace
}  // namespace fvm::stage
