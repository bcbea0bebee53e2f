// XFYZ machine tool with a laser tracker on the table, against [Aguado 2016] eq. 1 (last term X).

#include <gtest/gtest.h>

#include <Eigen/LU>

#include "stage/parameter_layout.h"
#include "tests/stage/written_out_machine.h"
#include "tests/support/test_models.h"

namespace fvm::stage {
namespace {

using testing::SmallRotation;

struct TrackedMachine {
  ParameterLayout layout;
  std::vector<double> free;
  Pose tracker;
  Eigen::Vector3d tool;
};

TrackedMachine MakeSetup(RotationModel model) {
  AxisChain chain = AxisChain::Parse("XFYZ");
  chain.rotation_model = model;
  chain.tool_offset = Eigen::Vector3d(10.0, -5.0, -150.0);
  // Tracker pose of [Aguado 2017] (section 3): T = (-863.527, 194.373, 677.782) mm, XYZ Euler angles in degrees.
  chain.instrument = Pose::FromEulerXyzDegrees({-863.527, 194.373, 677.782}, {0.0339, 0.0343, 59.4652});
  const std::array<Travel, 3> travel{Travel{0, 2500}, Travel{0, 1500}, Travel{0, 1200}};  // [IJSIMM 2016] workspace
  ParameterLayout layout = testing::FullLayout(chain, travel, 2, "xyz", Basis::kLegendre);
  std::vector<double> free = testing::RandomCoefficients(layout, 21, 0.03, 2e-5);
  const Pose tracker = *chain.instrument;
  const Eigen::Vector3d tool = chain.tool_offset;
  return {std::move(layout), std::move(free), tracker, tool};
}

// [Aguado 2016] eq. 1 written out: X_LT = R_LT^-1 (R_X^-1 (R_Y (R_Z T + Z) + Y - X) - T_LT).
Eigen::Vector3d SeedEquation(const TrackedMachine& s, const Eigen::Vector3d& q, bool transpose_for_inverse) {
  std::vector<double> all(s.layout.coefficients().size());
  s.layout.Expand(s.free.data(), all.data());
  double e[kNumErrorTerms];
  s.layout.TermValues(all.data(), q, e);
  const auto term = [&](const char* name) { return e[*FindErrorTerm(name)]; };
  const double x = q.x(), y = q.y(), z = q.z();
  const Eigen::Vector3d xv(-x + term("xTx"), term("xTy"), term("xTz"));
  const Eigen::Vector3d yv(term("yTx") - y * term("xWy"), y + term("yTy"), term("yTz"));
  const Eigen::Vector3d zv(term("zTx") - z * term("xWz"), term("zTy") - z * term("yWz"), z + term("zTz"));
  const Eigen::Matrix3d rx = SmallRotation({term("xRx"), term("xRy"), term("xRz")});
  const Eigen::Matrix3d ry = SmallRotation({term("yRx"), term("yRy"), term("yRz")});
  const Eigen::Matrix3d rz = SmallRotation({term("zRx"), term("zRy"), term("zRz")});
  const Eigen::Matrix3d rx_inv = transpose_for_inverse ? Eigen::Matrix3d(rx.transpose()) : Eigen::Matrix3d(rx.inverse());
  const Eigen::Vector3d part = rx_inv * (ry * (rz * s.tool + zv) + yv - xv);
  return s.tracker.Rotation().transpose() * (part - s.tracker.translation);
}

std::vector<Eigen::Vector3d> Mesh() {  // the 500/500/400 mm mesh of [IJSIMM 2016] section 5: 6 x 4 x 4 = 96 points
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i <= 5; ++i)
    for (int j = 0; j <= 3; ++j)
      for (int k = 0; k <= 3; ++k) q.emplace_back(500.0 * i, 500.0 * j, 400.0 * k);
  return q;
}

TEST(MachineToolChain, XfyzWithTrackerReproducesTheSeedEquation) {
  const TrackedMachine s = MakeSetup(RotationModel::kSmallAngle);
  for (const Eigen::Vector3d& q : Mesh()) {
    // Same equation, same small-angle matrices: only rounding of ~3000 mm coordinates separates them.
    EXPECT_LT((Forward(s.layout, s.free, q) - SeedEquation(s, q, false)).norm(), 1e-10);
  }
}

TEST(MachineToolChain, SeedConventionsAgreeToFirstOrder) {
  // Sources differ on how they invert R ([Pérez thesis] eq. 2.1 vs [IJSIMM 2016] eqs. 14-16); inverse and transpose of
  // I + [e]x differ by O(e^2), so every convention agrees with ours to first order: |e|^2 * |p| with |e| < 3 * 6e-5 rad
  // here.
  for (RotationModel model : {RotationModel::kSmallAngle, RotationModel::kExact}) {
    const TrackedMachine s = MakeSetup(model);
    double worst = 0.0;
    for (const Eigen::Vector3d& q : Mesh()) {
      const double diff = (Forward(s.layout, s.free, q) - SeedEquation(s, q, true)).norm();
      worst = std::max(worst, diff);
      EXPECT_LT(diff, std::pow(3 * 6e-5, 2) * 4000.0);
    }
    // ... and the first-order effect of the errors themselves is far larger than that gap.
    const Eigen::Vector3d q(2500, 1500, 1200);
    const Eigen::Vector3d nominal = s.tracker.Rotation().transpose() * (q + s.tool - s.tracker.translation);
    EXPECT_GT((SeedEquation(s, q, true) - nominal).norm(), 100 * worst);
  }
}

}  // namespace
}  // namespace fvm::stage
