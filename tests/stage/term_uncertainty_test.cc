// stage::TermValuesAt: the error functions the report of `fvm verify` draws, with their bands from the
// coefficient covariance, checked against sqrt(d^T C d) written out by hand for one term.

#include <gtest/gtest.h>

#include <cmath>

#include "stage/calibration.h"

namespace fvm::stage {
namespace {

// xTx of order 2 in the power basis on a travel 0..1000 mm: xTx(x) = c0 + c1 u + c2 u^2 with u = x / 500 (the
// power basis divides by the half travel), c0 fixed at zero (the pose absorbs it), c1 and c2 free and correlated.
Calibration Model() {
  ParameterLayout layout(AxisChain::Parse("XFYZ"), {Travel{0, 1000}, Travel{0, 500}, Travel{0, 400}});
  layout.SetTerm("xTx", Basis::kPower, 2);
  layout.SetTerm("xWy", Basis::kPower, 0);
  layout.Fix("xTx0", 0.0);
  Calibration cal{"test", layout, {0.010, -0.004, 2e-5}, Eigen::MatrixXd::Zero(3, 3), 0, std::nullopt, {}};
  // u(c1) = 2 um, u(c2) = 3 um, correlation -0.5; u(xWy) = 1 urad.
  cal.covariance << 4e-12, -3e-12, 0, -3e-12, 9e-12, 0, 0, 0, 1e-12;
  return cal;
}

TEST(TermValuesAt, BandIsSqrtDtCdOfTheTermAgainstItsValueAtTheOrigin) {
  const Calibration cal = Model();
  const int xtx = *FindErrorTerm("xTx");
  ASSERT_EQ(cal.layout.FreeNames(), (std::vector<std::string>{"xTx1", "xTx2", "xWy"}));
  const double u = [&] {
    const Eigen::Vector3d q(750, 100, 50);
    const Eigen::Vector3d origin(0, 0, 0);
    const TermValuesWithUncertainty t = TermValuesAt(cal, q, &origin);
    // By hand: at x = 750, u = 1.5: d = (1.5, 2.25, 0); at the origin d = 0.
    const double v1 = 4e-12, v2 = 9e-12, c12 = -3e-12;
    const double expected = std::sqrt(1.5 * 1.5 * v1 + 2.25 * 2.25 * v2 + 2 * 1.5 * 2.25 * c12);
    EXPECT_NEAR(t.value[xtx], 0.010 * 1.5 - 0.004 * 2.25, 1e-15);
    EXPECT_NEAR(t.u[xtx], expected, 1e-18);
    return t.u[xtx];
  }();
  EXPECT_GT(u, 0.0);
  // Relative to the origin the band closes there; the squareness is a constant with its own u.
  const Eigen::Vector3d origin(0, 0, 0);
  EXPECT_EQ(TermValuesAt(cal, origin, &origin).u[xtx], 0.0);
  const TermValuesWithUncertainty absolute = TermValuesAt(cal, Eigen::Vector3d(300, 0, 0));
  const int xwy = *FindErrorTerm("xWy");
  EXPECT_DOUBLE_EQ(absolute.value[xwy], 2e-5);
  EXPECT_DOUBLE_EQ(absolute.u[xwy], 1e-6);
  // Terms the layout does not hold: zero, with no band.
  EXPECT_EQ(absolute.value[*FindErrorTerm("yRz")], 0.0);
  EXPECT_EQ(absolute.u[*FindErrorTerm("yRz")], 0.0);
}

}  // namespace
}  // namespace fvm::stage
