// The generic chain against the published YXFZ stage model ([Pérez 2019] eqs. 1-5, and its eq. 13
// with the +yTy sign typo corrected).

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "stage/parameter_layout.h"
#include "tests/stage/published_model.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

using testing::FullLayout;
using testing::PublishedEquation1;
using testing::PublishedErrors;
using testing::RandomCoefficients;

// Order-1 power polynomials in the layout's normalised coordinate u = q / half-travel (= q / 100 here).
PublishedErrors ErrorsAt(const ParameterLayout& layout, const std::vector<double>& free, double x, double y) {
  const auto c = [&](const char* name) { return free[static_cast<size_t>(layout.FreeIndexOf(name))]; };
  const double ux = x / 100.0;
  const double uy = y / 100.0;
  const auto poly = [&](const std::string& n, double u) { return c((n + "0").c_str()) + c((n + "1").c_str()) * u; };
  return {poly("xTx", ux), poly("xTy", ux), poly("xTz", ux), poly("yTx", uy), poly("yTy", uy), poly("yTz", uy),
          poly("xRx", ux), poly("xRy", ux), poly("xRz", ux), poly("yRx", uy), poly("yRy", uy), poly("yRz", uy),
          c("xWy"),        c("xWz"),        c("yWz")};
}

// Eq. 13, the first-order expansion, with YP = y - xTy - yTy (the printed +yTy is a sign typo).
Eigen::Vector3d PublishedEquation13(const PublishedErrors& e, const Eigen::Vector3d& q) {
  Eigen::Matrix3d m;
  m << 0, e.yRz + e.xRz, -e.xRy - e.yRy,
       -e.xRz + e.xWy, 0, e.xRx + e.yRx,
       e.xRy + e.xWz, -e.yRx - e.xRx + e.yWz, 0;
  return q - Eigen::Vector3d(e.xTx + e.yTx, e.xTy + e.yTy, e.xTz + e.yTz) + m * q;
}

std::vector<Eigen::Vector3d> StagePositions(unsigned seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> xy(-200.0, 0.0), z(-60.0, -40.0);
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < n; ++i) q.emplace_back(xy(rng), xy(rng), z(rng));
  return q;
}

ParameterLayout PublishedOrder1Layout() {
  return FullLayout(AxisChain::FvmStage(), {Travel{-100, 100}, Travel{-100, 100}, Travel{-100, 100}}, 1);
}

TEST(PublishedModel, GenericChainReproducesEquations1To5ToMachinePrecision) {
  const ParameterLayout layout = PublishedOrder1Layout();
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<double> free = RandomCoefficients(layout, seed);
    for (const Eigen::Vector3d& q : StagePositions(seed, 50)) {
      const Eigen::Vector3d expected = PublishedEquation1(ErrorsAt(layout, free, q.x(), q.y()), q);
      // Coordinates of 200 mm carry 3e-14 mm of rounding; a few operations stay well inside 1e-12 mm.
      EXPECT_LT((Forward(layout, free, q) - expected).norm(), 1e-12) << "seed " << seed;
    }
  }
}

TEST(PublishedModel, FirstOrderExpansionDiffersOnlyBySecondOrderTerms) {
  const ParameterLayout layout = PublishedOrder1Layout();
  const std::vector<double> free = RandomCoefficients(layout, 11);
  double worst_full = 0.0;
  double worst_half = 0.0;
  for (const Eigen::Vector3d& q : StagePositions(11, 200)) {
    const PublishedErrors e = ErrorsAt(layout, free, q.x(), q.y());
    const double diff = (Forward(layout, free, q) - PublishedEquation13(e, q)).norm();
    // Second-order size: rotation x translation error + rotation^2 x coordinate. On these draws (u = q / 100
    // reaches 2) |T| <= 0.15 + 2 * 0.15 mm and |R| <= 2e-4 + 2 * 2e-4 rad per axis, summed over two axes.
    const double rot = 2 * 6e-4, trans = 2 * 0.45 + 300 * 2e-4;
    EXPECT_LT(diff, 4 * (rot * trans + rot * rot * q.norm()));
    worst_full = std::max(worst_full, diff);
    // Halving every error must quarter the gap if it is second order.
    std::vector<double> half = free;
    for (double& v : half) v *= 0.5;
    const PublishedErrors eh = ErrorsAt(layout, half, q.x(), q.y());
    worst_half = std::max(worst_half, (Forward(layout, half, q) - PublishedEquation13(eh, q)).norm());
  }
  EXPECT_GT(worst_full, 1e-7);  // the gap is real, not rounding
  EXPECT_NEAR(worst_half / worst_full, 0.25, 0.03);
}

TEST(PublishedModel, ExactRotationsDifferFromSmallAnglesOnlyAtSecondOrder) {
  ParameterLayout small = PublishedOrder1Layout();
  AxisChain exact_chain = AxisChain::FvmStage();
  exact_chain.rotation_model = RotationModel::kExact;
  const ParameterLayout exact = FullLayout(exact_chain, small.travel(), 1);
  const std::vector<double> free = RandomCoefficients(small, 5);
  for (const Eigen::Vector3d& q : StagePositions(5, 50)) {
    const double diff = (Forward(small, free, q) - Forward(exact, free, q)).norm();
    EXPECT_LT(diff, 2 * std::pow(2 * 6e-4, 2) * q.norm());  // |R - exp(R)| ~ |eps|^2 / 2 per axis
  }
}

}  // namespace
}  // namespace fvm::stage
