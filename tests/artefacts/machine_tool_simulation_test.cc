#include "artefacts/simulation/machine_tool_simulation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <set>

#include "artefacts/io/machine_truth_file.h"
#include "core/input_error.h"
#include "stage/pose.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;
using ::testing::HasSubstr;

const Workspace kPublished{Eigen::Vector3d::Zero(), Eigen::Vector3d(2500, 1500, 1200)};  // [IJSIMM 2016] section 5

// [IJSIMM 2016] Table I, position 4 (the optimised one): 1100, -1000, 600 mm; 63, 14, 35 deg.
stage::AxisChain PublishedChain() {
  stage::AxisChain chain = stage::AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0, 0, 100);
  chain.instrument = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(1100, -1000, 600), Eigen::Vector3d(63, 14, 35));
  return chain;
}

TEST(MachineToolPlan, PublishedMeshesHave96And5408Points) {
  const auto coarse = PlanMesh(kPublished, Eigen::Vector3d(500, 500, 400));
  ASSERT_EQ(coarse.size(), 96u);  // 6 x 4 x 4
  EXPECT_EQ(PlanMesh(kPublished, Eigen::Vector3d(100, 100, 100)).size(), 5408u);  // 26 x 16 x 13
  EXPECT_EQ(coarse.front().id, "P0001");
  EXPECT_EQ(coarse.back().id, "P0096");
  std::set<std::tuple<double, double, double>> distinct;
  for (const auto& p : coarse) distinct.insert({p.nominal.x(), p.nominal.y(), p.nominal.z()});
  EXPECT_EQ(distinct.size(), 96u);
}

TEST(MachineToolPlan, MeshIsSerpentineWithXFastestAndApproachFromTheLastXMotion) {
  const auto mesh = PlanMesh(kPublished, Eigen::Vector3d(500, 500, 400));
  // Every move changes one axis by one step: no jump back along a row or a layer.
  for (size_t i = 1; i < mesh.size(); ++i) {
    const Eigen::Vector3d d = (mesh[i].nominal - mesh[i - 1].nominal).cwiseAbs();
    EXPECT_EQ((d.array() > 0).count(), 1) << mesh[i].id;
    EXPECT_TRUE(d.x() == 500 || d.y() == 500 || d.z() == 400) << mesh[i].id;
  }
  EXPECT_EQ(mesh[0].nominal, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(mesh[5].nominal, Eigen::Vector3d(2500, 0, 0));   // first row runs +x
  EXPECT_EQ(mesh[6].nominal, Eigen::Vector3d(2500, 500, 0));  // second row starts where the first ended
  EXPECT_EQ(mesh[11].nominal, Eigen::Vector3d(0, 500, 0));
  EXPECT_EQ(mesh[24].nominal, Eigen::Vector3d(0, 1500, 400));  // the second layer starts above the end of the first
  EXPECT_EQ(mesh[0].approach, "+x");
  EXPECT_EQ(mesh[5].approach, "+x");
  EXPECT_EQ(mesh[6].approach, "+x");  // only Y moved: X last moved +x
  EXPECT_EQ(mesh[7].approach, "-x");
}

TEST(MachineToolPlan, ATravelThatIsNoMultipleOfTheStepEndsOnItsMaximum) {
  const Workspace ws{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1050, 300, 200)};
  const auto mesh = PlanMesh(ws, Eigen::Vector3d(500, 300, 200));
  ASSERT_EQ(mesh.size(), 4u * 2 * 2);  // x: 0, 500, 1000, 1050
  EXPECT_EQ(mesh[3].nominal.x(), 1050);
}

TEST(MachineToolPlan, CloudStaysInItsCellsKeepsTheBoundaryAndIsSeeded) {
  const Eigen::Vector3d step(500, 500, 400);
  const auto mesh = PlanMesh(kPublished, step);
  const auto cloud = PlanCloud(kPublished, step, 7);
  ASSERT_EQ(cloud.size(), mesh.size());
  int moved = 0;
  for (size_t i = 0; i < mesh.size(); ++i) {
    EXPECT_EQ(cloud[i].id, mesh[i].id);
    for (int k = 0; k < 3; ++k) {
      const double node = mesh[i].nominal[k];
      const double v = cloud[i].nominal[k];
      if (node == kPublished.min[k] || node == kPublished.max[k]) {
        EXPECT_EQ(v, node) << cloud[i].id << " axis " << k;  // eq. 18: boundary coordinates stay
      } else {
        EXPECT_LE(std::abs(v - node), 0.5 * step[k]) << cloud[i].id << " axis " << k;
        EXPECT_EQ(v, std::round(v * 1000) / 1000);  // whole micrometres, as the program writes them
        moved += v != node;
      }
    }
  }
  EXPECT_GT(moved, 100);  // 4 * 2 * 2 interior nodes per ... every interior coordinate moves (144 of them)
  const auto again = PlanCloud(kPublished, step, 7);
  const auto other = PlanCloud(kPublished, step, 8);
  bool same = true, differs = false;
  for (size_t i = 0; i < cloud.size(); ++i) {
    same = same && cloud[i].nominal == again[i].nominal && cloud[i].approach == again[i].approach;
    differs = differs || cloud[i].nominal != other[i].nominal;
  }
  EXPECT_TRUE(same);
  EXPECT_TRUE(differs);
  // The approach follows the actual X motions.
  for (size_t i = 1; i < cloud.size(); ++i) {
    const double dx = cloud[i].nominal.x() - cloud[i - 1].nominal.x();
    if (dx != 0) {
      EXPECT_EQ(cloud[i].approach, dx > 0 ? "+x" : "-x") << cloud[i].id;
    }
  }
}

TEST(MachineToolPlan, DiagonalsRunCornerToCorner) {
  const auto d = PlanDiagonals(kPublished, 5);
  ASSERT_EQ(d.size(), 20u);
  EXPECT_EQ(d[0].nominal, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(d[4].nominal, Eigen::Vector3d(2500, 1500, 1200));
  EXPECT_EQ(d[2].nominal, Eigen::Vector3d(1250, 750, 600));
  EXPECT_EQ(d[5].nominal, Eigen::Vector3d(2500, 0, 0));
  EXPECT_EQ(d[9].nominal, Eigen::Vector3d(0, 1500, 1200));
  EXPECT_EQ(d[6].approach, "-x");
  EXPECT_EQ(d[19].nominal, Eigen::Vector3d(0, 0, 1200));
  EXPECT_THROW(PlanDiagonals(kPublished, 1), std::invalid_argument);
}

TEST(MachineToolPlan, GCodeVisitsEveryPointWithItsDwell) {
  const auto mesh = PlanMesh(kPublished, Eigen::Vector3d(500, 500, 400));
  const std::string program = GCodeProgram(mesh, 6.0, 2000.0);
  EXPECT_EQ(program.rfind("%\n", 0), 0u);
  EXPECT_THAT(program, HasSubstr("G90 G21"));
  EXPECT_THAT(program, HasSubstr("G0 X0.000 Y0.000 Z0.000 (P0001 +x)\nG4 P6\n"));
  EXPECT_THAT(program, HasSubstr("G1 X500.000 Y0.000 Z0.000 F2000 (P0002 +x)\n"));
  EXPECT_THAT(program, HasSubstr("G1 X2500.000 Y500.000 Z0.000 (P0007 +x)\n"));
  EXPECT_THAT(program, HasSubstr("M30\n%\n"));
  size_t dwells = 0, moves = 0;
  for (size_t at = program.find("\nG4 P6\n"); at != std::string::npos; at = program.find("\nG4 P6\n", at + 1)) ++dwells;
  for (size_t at = program.find("\nG"); at != std::string::npos; at = program.find("\nG", at + 1)) {
    moves += program.compare(at + 1, 3, "G0 ") == 0 || program.compare(at + 1, 3, "G1 ") == 0;
  }
  EXPECT_EQ(dwells, 96u);
  EXPECT_EQ(moves, 96u);
  EXPECT_THROW(GCodeProgram(mesh, -1.0), std::invalid_argument);
}

TEST(MachineTruth, VanishesAtTheOriginAndHasTheRequestedMeanError) {
  const stage::AxisChain chain = PublishedChain();
  const MachineTruth truth = RandomMachineTruth(chain, kPublished, 3, 35.0);
  double e[stage::kNumErrorTerms];
  TermValuesAt(truth, kPublished.min, e);
  for (int t = 0; t < stage::kFirstSquarenessTerm; ++t) {
    EXPECT_NEAR(e[t], 0.0, 1e-15) << stage::GetErrorTerm(t).vdi;  // mm or rad; rounding of -A sin(phi) + A sin(phi)
  }
  EXPECT_LT(VolumetricErrorMm(chain, truth, kPublished.min), 1e-12);
  // The mean over the 11 x 11 x 11 mesh it was scaled on: within 1 % (by construction to rounding).
  const auto grid = PlanMesh(kPublished, (kPublished.max - kPublished.min) / 10.0);
  ASSERT_EQ(grid.size(), 1331u);
  EXPECT_NEAR(VolumetricErrorSummary(chain, truth, grid).mean_um(), 35.0, 0.35);
  // Another size, another chain.
  stage::AxisChain other = stage::AxisChain::Parse("YXFZ");
  EXPECT_NEAR(VolumetricErrorSummary(other, RandomMachineTruth(other, kPublished, 4, 120.0), grid).mean_um(), 120.0, 1.2);
  // The finer published mesh (5408 points) sees about the same mean: within 10 % (a different sample of one field).
  const auto fine = PlanMesh(kPublished, Eigen::Vector3d(100, 100, 100));
  EXPECT_NEAR(VolumetricErrorSummary(chain, truth, fine).mean_um(), 35.0, 3.5);
  // The published-machine overload is the same as XFYZ with the 100 mm tool.
  const MachineTruth plain = RandomMachineTruth(kPublished, 3, 35.0);
  EXPECT_EQ(plain.terms[0].poly, truth.terms[0].poly);
}

TEST(MachineTruth, IsSeeded) {
  const MachineTruth a = RandomMachineTruth(kPublished, 11);
  const MachineTruth b = RandomMachineTruth(kPublished, 11);
  const MachineTruth c = RandomMachineTruth(kPublished, 12);
  for (int t = 0; t < stage::kNumErrorTerms; ++t) {
    EXPECT_EQ(a.terms[t].poly, b.terms[t].poly);
    EXPECT_EQ(a.terms[t].sine_phase_rad, b.terms[t].sine_phase_rad);
  }
  EXPECT_NE(a.terms[0].poly, c.terms[0].poly);
}

// Residual rms of the least-squares cubic through the term over its travel, and the term's sine amplitude.
double CubicFitResidualRms(const TermTruth& term, double travel) {
  constexpr int n = 4001;
  Eigen::MatrixXd a(n, 4);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    const double u = travel * i / (n - 1);
    const double x = u / travel;  // normalised, for conditioning
    a.row(i) << 1, x, x * x, x * x * x;
    y[i] = term.Value(u);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(y);
  return std::sqrt((y - a * c).squaredNorm() / n);
}

TEST(MachineTruth, ItsErrorsAreNotCubics) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const MachineTruth truth = RandomMachineTruth(kPublished, seed);
    for (int k = 0; k < 3; ++k) {
      const double travel = kPublished.max[k] - kPublished.min[k];
      // Positioning: a 10-40 mm screw period over 1200-2500 mm is 30-250 periods, orthogonal to any cubic: the
      // residual is the sine's rms, A / sqrt(2) = 0.71 A. Half the amplitude leaves room for the ends.
      const TermTruth& positioning = truth.terms[static_cast<size_t>(stage::TranslationTerm(static_cast<stage::Axis>(k), k))];
      ASSERT_GT(positioning.sine_amplitude, 0.0);
      EXPECT_GT(CubicFitResidualRms(positioning, travel), 0.5 * positioning.sine_amplitude) << "seed " << seed << " axis " << k;
      EXPECT_LT(positioning.sine_pitch_mm, 40.0 + 1e-9);
      // Straightness and rotation: 1.25 to 3.3 periods of a long wave. The worst case over the wavelengths and
      // phases the generator draws still leaves 16 % of the amplitude rms (LongWaveWorstCaseIsStillNotACubic);
      // 15 % is the bound.
      for (int t = 0; t < stage::kFirstSquarenessTerm; ++t) {
        if (static_cast<int>(stage::GetErrorTerm(t).axis) != k || t == stage::TranslationTerm(static_cast<stage::Axis>(k), k)) continue;
        const TermTruth& term = truth.terms[static_cast<size_t>(t)];
        EXPECT_GT(CubicFitResidualRms(term, travel), 0.15 * term.sine_amplitude) << stage::GetErrorTerm(t).vdi;
      }
    }
  }
}

TEST(MachineTruth, LongWaveWorstCaseIsStillNotACubic) {
  // The bound used above: over every wavelength the generator draws (0.3 .. 0.8 of the travel) and every phase.
  double worst = 1.0;
  for (int w = 0; w <= 50; ++w) {
    for (int p = 0; p < 36; ++p) {
      TermTruth term;
      term.sine_amplitude = 1.0;
      term.sine_pitch_mm = 1000.0 * (0.3 + 0.5 * w / 50.0);
      term.sine_phase_rad = 2 * std::numbers::pi * p / 36.0;
      worst = std::min(worst, CubicFitResidualRms(term, 1000.0));
    }
  }
  RecordProperty("worst_long_wave_residual", std::to_string(worst));  // 0.164
  EXPECT_GT(worst, 0.15);
}

TEST(TrackerSimulation, NoiseFreeReadingsAreTheChainInTheTrackerFrame) {
  const stage::AxisChain chain = PublishedChain();
  const MachineTruth truth = RandomMachineTruth(chain, kPublished, 5);
  const auto mesh = PlanMesh(kPublished, Eigen::Vector3d(500, 500, 400));
  TrackerReadings noise_free;
  const TrackerReadings noisy = SimulateTrackerReadings(chain, truth, mesh, stage::TrackerNoise::Preset("none"), 1, &noise_free);
  ASSERT_EQ(noisy.points.size(), 96u);
  ASSERT_EQ(noise_free.points.size(), 96u);
  const Eigen::Matrix3d r = chain.instrument->Rotation();
  for (size_t i = 0; i < mesh.size(); ++i) {
    EXPECT_EQ(noisy.points[i].measured, noise_free.points[i].measured);  // preset none: no noise
    EXPECT_EQ(noisy.points[i].id, mesh[i].id);
    EXPECT_EQ(noisy.points[i].approach, mesh[i].approach);
    // By hand: displaced tool point in the machine frame, then R^T (p - t).
    const Eigen::Vector3d tool = mesh[i].nominal + chain.tool_offset;
    const Eigen::Vector3d nominal_in_tracker = r.transpose() * (tool - chain.instrument->translation);
    const double displaced = (noisy.points[i].measured - nominal_in_tracker).norm();
    EXPECT_NEAR(displaced, VolumetricErrorMm(chain, truth, mesh[i].nominal), 1e-9);
  }
  // All 96 points are visible from [IJSIMM 2016] Table I position 4.
  EXPECT_TRUE(PointsBeyondTrackerLimits(noisy, *chain.instrument).empty());
}

TEST(TrackerSimulation, NoiseHasTheTrackerCovarianceAndIsSeeded) {
  const stage::AxisChain chain = PublishedChain();
  const MachineTruth truth = RandomMachineTruth(chain, kPublished, 5);
  const stage::TrackerNoise noise = stage::TrackerNoise::Preset("published");
  constexpr int n = 20000;
  PlannedPoint corner{"C", Eigen::Vector3d(2500, 1500, 1200), "+x"};
  std::vector<PlannedPoint> repeats(n, corner);
  TrackerReadings truths;
  const TrackerReadings r = SimulateTrackerReadings(chain, truth, repeats, noise, 42, &truths);
  const Eigen::Vector3d exact = truths.points[0].measured;
  const Eigen::Matrix3d expected = noise.Covariance(exact);
  // Whitened by the expected covariance the samples must have unit covariance. With n = 20000 a variance's
  // relative standard error is sqrt(2/n) = 1 % and a correlation's 1/sqrt(n) = 0.7 %: 5 % is five of them (and the
  // brief's 10 %); the mean is within 5 standard errors (5 / sqrt(n) = 0.035 whitened units).
  const Eigen::Matrix3d l_inverse = expected.llt().matrixL().solve(Eigen::Matrix3d::Identity());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : r.points) mean += l_inverse * (p.measured - exact);
  mean /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : r.points) {
    const Eigen::Vector3d w = l_inverse * (p.measured - exact) - mean;
    cov += w * w.transpose();
  }
  cov /= n - 1;
  EXPECT_LT(mean.cwiseAbs().maxCoeff(), 0.035) << mean.transpose();
  EXPECT_LT((cov - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 0.05) << cov;
  // The spread in mm: range sigma along the beam, 24 urad * range across it in elevation, 24 urad * range *
  // cos(elevation) in azimuth (the horizontal circle is smaller).
  const stage::Spherical s = stage::ToSpherical(exact);
  const double across = 24e-6 * s.range_mm;
  EXPECT_NEAR(expected.trace(),
              std::pow(noise.RangeSigmaMm(s.range_mm), 2) + across * across * (1 + std::pow(std::cos(s.elevation_rad), 2)),
              1e-12);

  const TrackerReadings again = SimulateTrackerReadings(chain, truth, repeats, noise, 42);
  const TrackerReadings other = SimulateTrackerReadings(chain, truth, repeats, noise, 43);
  bool same = true;
  for (int i = 0; i < n; ++i) same = same && again.points[static_cast<size_t>(i)].measured == r.points[static_cast<size_t>(i)].measured;
  EXPECT_TRUE(same);  // bit for bit
  EXPECT_NE(other.points[0].measured, r.points[0].measured);
}

TEST(TrackerSimulation, PointsOutOfSightAreNamed) {
  TrackerReadings r;
  TrackerReading up;
  up.id = "P0003";
  up.measured = Eigen::Vector3d(100, 0, 1000);  // 84 deg up
  TrackerReading far;
  far.id = "P0004";
  far.measured = Eigen::Vector3d(50'000, 0, 0);
  TrackerReading fine;
  fine.id = "P0005";
  fine.measured = Eigen::Vector3d(3000, 0, -1000);
  r.points = {up, far, fine};
  const auto beyond = PointsBeyondTrackerLimits(r, stage::Pose{});
  // The elevation is the levelled head's, against the machine's horizontal: the same points in a frame turned
  // 90 deg about x read as level in that frame but stay out of sight.
  TrackerReadings turned = r;
  const stage::Pose quarter = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d::Zero(), Eigen::Vector3d(90, 0, 0));
  for (auto& p : turned.points) p.measured = quarter.Rotation().transpose() * p.measured;
  EXPECT_EQ(PointsBeyondTrackerLimits(turned, quarter), beyond);
  ASSERT_EQ(beyond.size(), 2u);
  EXPECT_THAT(beyond[0], HasSubstr("P0003: elevation 84.3 deg above"));
  EXPECT_THAT(beyond[1], HasSubstr("P0004: range"));
  stage::AxisChain no_pose = stage::AxisChain::Parse("XFYZ");
  EXPECT_THROW(SimulateTrackerReadings(no_pose, MachineTruth{}, {}, stage::TrackerNoise{}, 1), std::invalid_argument);
}

TEST(MachineTruthFile, RoundTripsExactly) {
  const MachineTruth truth = RandomMachineTruth(kPublished, 9);
  const MachineTruth back = ParseMachineTruth(MachineTruthJson(truth), "truth.json", kPublished);
  for (size_t t = 0; t < truth.terms.size(); ++t) {
    EXPECT_EQ(back.terms[t].poly, truth.terms[t].poly) << t;
    EXPECT_EQ(back.terms[t].sine_amplitude, truth.terms[t].sine_amplitude) << t;
    EXPECT_EQ(back.terms[t].sine_pitch_mm, truth.terms[t].sine_pitch_mm) << t;
    EXPECT_EQ(back.terms[t].sine_phase_rad, truth.terms[t].sine_phase_rad) << t;
  }
}

TEST(MachineTruthFile, ReadsNamesAliasesAndDefaults) {
  const MachineTruth t = ParseMachineTruth(
      R"({"note": "ignored", "terms": {"xTx": {"poly": [0, 1e-5], "sine": {"amplitude": 0.002, "pitch_mm": 20}},
          "EYX": {"poly": [0, 0, 1e-9]}, "xWy": {"poly": [2e-5]}}})",
      "e.json", kPublished);
  double e[stage::kNumErrorTerms];
  TermValuesAt(t, Eigen::Vector3d(105, 0, 0), e);
  EXPECT_NEAR(e[*stage::FindErrorTerm("xTx")], 1e-5 * 105 + 0.002 * std::sin(2 * std::numbers::pi * 105 / 20), 1e-15);
  EXPECT_NEAR(e[*stage::FindErrorTerm("xTy")], 1e-9 * 105 * 105, 1e-15);  // EYX is xTy
  EXPECT_EQ(e[*stage::FindErrorTerm("xWy")], 2e-5);
  EXPECT_EQ(e[*stage::FindErrorTerm("zRz")], 0.0);
}

TEST(MachineTruthFile, RefusesWithTheFileAndTerm) {
  const auto refuse = [](const std::string& text) {
    return InputErrorOf([&] { ParseMachineTruth(text, "e.json", kPublished); });
  };
  EXPECT_THAT(refuse("{"), HasSubstr("e.json:1: not valid JSON"));
  EXPECT_THAT(refuse(std::string(100, '[')), HasSubstr("e.json:1: arrays and objects nested deeper than 64 levels"));
  EXPECT_THAT(refuse(R"({"poly": []})"), HasSubstr("\"terms\""));
  EXPECT_THAT(refuse(R"({"terms": {"xQx": {"poly": [0]}}})"), HasSubstr("unknown error term 'xQx'"));
  EXPECT_THAT(refuse(R"({"terms": {"xTx": {"poly": [0]}, "EXX": {"poly": [0]}}})"), HasSubstr("given twice"));
  EXPECT_THAT(refuse(R"({"terms": {"xTx": {"polly": [0]}}})"), HasSubstr("term xTx: unknown key 'polly'"));
  EXPECT_THAT(refuse(R"({"terms": {"xTx": {"poly": [0, 1, 2, 3, 4]}}})"), HasSubstr("1 to 4 coefficients"));
  EXPECT_THAT(refuse(R"({"terms": {"xTx": {"poly": ["a"]}}})"), HasSubstr("not a number"));
  EXPECT_THAT(refuse(R"({"terms": {"xWy": {"poly": [0, 1e-9]}}})"), HasSubstr("one angle"));
  EXPECT_THAT(refuse(R"({"terms": {"xWy": {"poly": [0], "sine": {"amplitude": 1, "pitch_mm": 2}}}})"), HasSubstr("no sine"));
  EXPECT_THAT(refuse(R"({"terms": {"yTy": {"poly": [0], "sine": {"amplitude": 0.001, "pitch_mm": 0}}}})"),
              HasSubstr("pitch_mm = 0 must be positive"));
  EXPECT_THAT(refuse(R"({"terms": {"zTz": {"poly": [0, 0.02]}}})"), HasSubstr("term zTz reaches"));  // um/mm as mm/mm
  EXPECT_THAT(refuse(R"({"terms": {"xRz": {"poly": [20]}}})"), HasSubstr("urad given?"));
  EXPECT_THAT(refuse(R"({"workspace": {"min_mm": [0, 0, -500]}, "terms": {}})"), HasSubstr("origin"));
}

}  // namespace
}  // namespace fvm::artefacts
