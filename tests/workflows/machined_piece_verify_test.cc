#include "workflows/machined_piece_verify.h"

#include <gtest/gtest.h>

#include <set>

#include "tests/support/test_support.h"
#include "artefacts/geometry/machined_piece.h"
#include "artefacts/simulation/machined_piece_simulation.h"

namespace fvm::workflows {
namespace {

constexpr double kCmmNoiseUm = 1.0;

// The published piece cut by [Lorente 2021] Table 4's machine (quadratic errors: an order-2 model takes them),
// measured on a CMM with 1 um of noise per coordinate at a datum turned 12 deg, with a noise-free validation grid.
struct MeasuredPiece {
  fvm::testing::TempDir dir;
  MachineProblemOptions options;
  std::string nominal;

  MeasuredPiece() {
    const artefacts::MachinedPieceDescription piece = artefacts::PublishedMachinedPiece();
    const std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(piece);
    stage::AxisChain chain = stage::AxisChain::Parse("XFYZ");
    chain.tool_offset = Eigen::Vector3d(0, 0, 100);
    const artefacts::Workspace ws = artefacts::PieceWorkspace(piece);
    const artefacts::MachineTruth truth = artefacts::PublishedTestFunctions(ws);
    artefacts::CmmSimulation cmm;
    cmm.datum = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(20, -15, 5), Eigen::Vector3d(0.05, -0.1, 12));
    cmm.sigma_mm = kCmmNoiseUm * 1e-3;
    cmm.seed = 41;
    artefacts::TrackerReadings noise_free;
    const artefacts::TrackerReadings measured = artefacts::SimulateMachinedPiece(chain, truth, points, cmm, &noise_free);
    artefacts::WriteTrackerReadings(dir.path() / "measured.csv", measured);
    nominal = (dir.path() / "nominal.csv").string();
    artefacts::WriteNominalPoints(nominal, points);
    std::vector<artefacts::PiecePoint> grid;
    for (const artefacts::PlannedPoint& p : artefacts::PlanMesh(ws, Eigen::Vector3d::Constant(50))) {
      std::string id = p.id;  // P0001 -> G0001
      id[0] = 'G';
      grid.push_back({id, p.nominal, "", "", {}});
    }
    cmm.sigma_mm = 0;
    artefacts::WriteTrackerReadings(dir.path() / "validation.csv", artefacts::SimulateMachinedPiece(chain, truth, grid, cmm));
    options.data = (dir.path() / "measured.csv").string();
    options.validate = (dir.path() / "validation.csv").string();
    options.basis = "chebyshev";
    options.tools = {chain.tool_offset};
    options.tracker = "none";
    options.unweighted = true;
  }
};

// The machine's errors leave the CMM noise alone: the mean 3-D residual of N(0, s^2 I) is 2 sqrt(2 / pi) s = 1.60 s,
// a little less for the ~50 parameters of 3 x 480 equations; over 480 points its mean has a standard deviation of
// 0.67 s / sqrt(480) = 0.03 s, so 1.4-1.75 um is 5 of them. On the noise-free grid what is left is the model's
// uncertainty, s sqrt(p / N) = 0.3 um: below 0.5 um, from about 100 um before.
TEST(VerifyMachinedPiece, LeavesTheCmmNoiseOnThePieceAndTheModelUncertaintyOnTheGrid) {
  const MeasuredPiece piece;
  const MachinedPieceVerifyResult r = VerifyMachinedPiece(LoadMachineProblem(piece.options), {.order = 2, .nominal = ""});
  const stage::MachinedPieceVerification& v = r.verification;
  ASSERT_TRUE(v.result.identified.converged);
  EXPECT_GT(v.result.final.mean_um(), 1.4 * kCmmNoiseUm);
  EXPECT_LT(v.result.final.mean_um(), 1.75 * kCmmNoiseUm);
  ASSERT_TRUE(r.validation.has_value());
  EXPECT_GT(r.validation->before.mean_um(), 50.0);
  EXPECT_LT(r.validation->after.mean_um(), 0.5);
  // The log starts at the ideal machine and ends at the final fit.
  ASSERT_GE(v.iterations.size(), 2u);
  EXPECT_DOUBLE_EQ(v.iterations.front().mean_um(), v.result.initial.mean_um());
  EXPECT_NEAR(v.iterations.back().mean_um(), v.result.final.mean_um(), 0.01);
  EXPECT_EQ(r.geometric_from, "all points");
  EXPECT_FALSE(r.extraction.has_value());
}

// The series X1..Z3 alone: [Lorente 2021] finds that they cannot give the Z yaws and roll-pitch of Z nor ECY
// (hence the proposed series with more tools); the job says the same and extracts errors from them.
TEST(VerifyMachinedPiece, TheSeriesAloneLeaveTheYawsOfZAndEcyUnrecovered) {
  const MeasuredPiece piece;
  const MachinedPieceVerifyResult r = VerifyMachinedPiece(LoadMachineProblem(piece.options), {.order = 2, .nominal = piece.nominal});
  EXPECT_EQ(r.geometric_from.rfind("series X1..Z3 (", 0), 0u) << r.geometric_from;
  std::set<std::string> lost;
  for (const stage::TermRecovery& t : r.geometric) {
    if (!t.recoverable && !t.partly) lost.insert(t.error);
  }
  EXPECT_EQ(lost, (std::set<std::string>{"ECY", "EAZ", "EBZ", "ECZ"}));
  ASSERT_TRUE(r.extraction.has_value());
  EXPECT_FALSE(r.extraction->empty());
}

TEST(VerifyMachinedPiece, ANominalFileWithoutSeriesIsRefusedNamingBothFiles) {
  const MeasuredPiece piece;
  const std::string other = (piece.dir.path() / "other.csv").string();
  artefacts::WriteNominalPoints(other, {{"Q1", Eigen::Vector3d(1, 2, 3), "X1", "", {}}});
  try {
    VerifyMachinedPiece(LoadMachineProblem(piece.options), {.order = 2, .nominal = other});
    FAIL() << "a nominal file without the piece's points was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), other + ": no point of " + piece.options.data +
                                         " belongs to a series X1..Z3; give the NOMINAL.csv of the same piece");
  }
}

}  // namespace
}  // namespace fvm::workflows
