// A scan's points corrected as centres are (issue 17): ScanCorrector gives the bits of stage::Correct and of
// FirstTileCompensation for the same coordinates, with any origin, on any number of threads; invalid points are
// counted and left alone; points beyond the travel are found.

#include "stage/scan_correction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stage/identification.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

Calibration Model(unsigned seed) {
  const ParameterLayout layout = testing::FullLayout(AxisChain::FvmStage(), testing::FvmTravel(), 1);
  const Eigen::Index n = layout.NumFree();
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1e-4);
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = normal(random);
  return Calibration{"27", layout, testing::RandomCoefficients(layout, seed), a * a.transpose(), 5e-4,
                     Eigen::Vector3d(-190.0, -10.0, -50.0), {}};
}

std::vector<Eigen::Vector3d> Points(int n) {
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> x(-190.0, -10.0), z(-50.5, -49.5);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(x(random), x(random), z(random));
  return points;
}

TEST(ScanCorrection, EveryPointIsTheCentreCorrectionOfItsCoordinates) {
  const Calibration cal = Model(1);
  const Eigen::Vector3d origin(-100.0, -120.0, -50.0);
  std::vector<Eigen::Vector3d> stage_points = Points(500), file_points;
  for (const Eigen::Vector3d& p : stage_points) file_points.push_back(p - origin);
  for (const bool first_tile : {false, true}) {
    SCOPED_TRACE(first_tile ? "first-tile" : "stage");
    ScanCorrectionOptions options;
    options.origin_mm = origin;
    if (first_tile) options.first_tile_frame = StitchedFrame::kRotated;
    const ScanCorrector corrector(cal, options, file_points);
    const FirstTileCompensation centres(cal, StitchedFrame::kRotated, FirstTile(stage_points));
    std::vector<Eigen::Vector3d> moved = file_points, u;
    moved[7] = Eigen::Vector3d::Constant(NAN);
    const ScanCorrectionSummary summary = CorrectScanInPlace(corrector, moved, &u, 2);
    EXPECT_EQ(summary.corrected, 499u);
    EXPECT_EQ(summary.invalid, 1u);
    EXPECT_TRUE(std::isnan(moved[7].x()) && std::isnan(u[7].x()));
    for (std::size_t i = 0; i < stage_points.size(); ++i) {
      if (i == 7) continue;
      const CorrectedPoint c = first_tile ? centres.Correct(stage_points[i]) : Correct(cal, stage_points[i]);
      // Through the origin and back: the stage point's correction, to the rounding of adding the origin twice.
      ASSERT_LT((moved[i] + origin - c.position).cwiseAbs().maxCoeff(), 1e-12) << i;
      const Eigen::Vector3d u_centre = c.covariance.diagonal().cwiseSqrt();
      ASSERT_LT((u[i] - u_centre).cwiseAbs().maxCoeff(), 1e-12 + 1e-9 * u_centre.norm()) << i;
      ASSERT_LT((corrector.Position(file_points[i]) - moved[i]).cwiseAbs().maxCoeff(), 1e-12) << i;
    }
  }
  // With a zero origin, the stage frame gives the very bits of stage::Correct.
  const ScanCorrector plain(cal, {}, stage_points);
  for (const Eigen::Vector3d& p : stage_points) {
    const Eigen::Vector3d a = plain.Correct(p).position, b = Correct(cal, p).position;
    ASSERT_EQ(a, b);
  }
}

TEST(ScanCorrection, SameBitsOnOneAndTwoThreads) {
  const Calibration cal = Model(2);
  const std::vector<Eigen::Vector3d> points = Points(20000);
  const ScanCorrector corrector(cal, {}, points);
  std::vector<Eigen::Vector3d> one = points, two = points, u1, u2;
  CorrectScanInPlace(corrector, one, &u1, 1);
  CorrectScanInPlace(corrector, two, &u2, 2);
  EXPECT_EQ(one, two);
  EXPECT_EQ(u1, u2);
}

TEST(ScanCorrection, PointsOutsideTheTravelAreFound) {
  const Calibration cal = Model(3);
  const std::vector<Eigen::Vector3d> points = {{-100, -100, -50}, {10, -100, -50}, {NAN, NAN, NAN}, {-100, -250, 0}};
  EXPECT_EQ(PointsOutsideTravel(cal.layout, points, Eigen::Vector3d::Zero()), (std::vector<std::size_t>{1, 3}));
  // z is not checked: the microscope model has no z errors to extrapolate.
  EXPECT_TRUE(PointsOutsideTravel(cal.layout, {{-100, -100, 500}}, Eigen::Vector3d::Zero()).empty());
  EXPECT_EQ(PointsOutsideTravel(cal.layout, {{-100, -100, 0}}, Eigen::Vector3d(150, 0, 0)), (std::vector<std::size_t>{0}));
}

}  // namespace
}  // namespace fvm::stage
