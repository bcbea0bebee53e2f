// The loops of a grid against one wrong pair (imaging/loop_misclosure.h): pairs with exact offsets around a 3 x 3
// grid, one of them 11 px off (a repeat of the pattern) and claiming far more precision than the others.

#include "imaging/loop_misclosure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "imaging/tile_registration.h"

namespace fvm::imaging {
namespace {

struct Grid3x3 {
  std::vector<Eigen::Vector2d> truth, stage;
  std::vector<PairRegistration> pairs;
};

// Tiles 0..8 row-major, steps of about 230 x 170 px; every pair exact with u = 0.01 px.
Grid3x3 MakeGrid() {
  Grid3x3 g;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      g.truth.emplace_back(230.0 * c + 3.0 * r + 0.25 * c * c, 170.0 * r - 4.0 * c + 0.5 * r * c);
      g.stage.emplace_back(230.0 * c, 170.0 * r);
    }
  }
  const auto add = [&](int a, int b) {
    PairRegistration p;
    p.a = a;
    p.b = b;
    p.nominal_px = g.stage[static_cast<size_t>(b)] - g.stage[static_cast<size_t>(a)];
    p.offset_px = g.truth[static_cast<size_t>(b)] - g.truth[static_cast<size_t>(a)];
    p.information = 1e4 * Eigen::Matrix2d::Identity();
    p.quality = 0.9;
    p.accepted = true;
    g.pairs.push_back(p);
  };
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (c < 2) add(3 * r + c, 3 * r + c + 1);
      if (r < 2) add(3 * r + c, 3 * r + c + 3);
    }
  }
  return g;
}

// The pair between tiles 4 and 5 (the middle row's east pair, in two loops).
size_t WrongPair(const Grid3x3& g) {
  for (size_t k = 0; k < g.pairs.size(); ++k) {
    if (g.pairs[k].a == 4 && g.pairs[k].b == 5) return k;
  }
  return 0;
}

TEST(LoopMisclosure, AWrongPairIsSearchedAgainWhereTheLoopsPutIt) {
  Grid3x3 g = MakeGrid();
  const size_t wrong = WrongPair(g);
  const Eigen::Vector2d true_offset = g.pairs[wrong].offset_px;
  g.pairs[wrong].offset_px += Eigen::Vector2d(11.0, 0.0);
  g.pairs[wrong].information = 1e8 * Eigen::Matrix2d::Identity();  // u = 0.0001 px: it claims to be sure
  g.pairs[wrong].quality = 0.95;                                     // and matches best
  int searched = 0;
  const auto research = [&](const PairRegistration& pair, const Eigen::Vector2d& predicted, const Eigen::Vector2d& window) {
    ++searched;
    PairRegistration found = pair;
    const Eigen::Vector2d truth = g.truth[static_cast<size_t>(pair.b)] - g.truth[static_cast<size_t>(pair.a)];
    found.accepted = ((truth - predicted).cwiseAbs() - window).maxCoeff() <= 0.0;
    found.offset_px = truth;
    found.information = 1e4 * Eigen::Matrix2d::Identity();
    return found;
  };
  const LoopCheck check = CheckPairsAgainstLoops(g.stage, 10.0, g.pairs, research);
  ASSERT_EQ(check.overruled.size(), 1u);
  EXPECT_EQ(check.overruled[0].pair, static_cast<int>(wrong));
  EXPECT_TRUE(check.overruled[0].replaced);
  // The others put it where it is, to their precision (two paths of three pairs of u = 0.01 px).
  EXPECT_NEAR(check.overruled[0].predicted_px.x(), true_offset.x(), 0.05);
  EXPECT_GT(check.overruled[0].misclosure_sigma, 100.0);
  EXPECT_TRUE(g.pairs[wrong].accepted);
  EXPECT_NEAR((g.pairs[wrong].offset_px - true_offset).norm(), 0.0, 1e-9);
  EXPECT_GE(searched, 1);
  // Once it is right, the loops close (but for the stage prior's pull of 1e-4 px on the 10 px it is off): the pairs
  // keep what they claim.
  EXPECT_LT(check.birge_ratio, 0.01);
  const TilePositions p = SolveTilePositions(g.stage, g.pairs, 10.0);
  for (size_t i = 0; i < 9; ++i) {
    EXPECT_NEAR((p.positions_px[i] - g.truth[i] - (p.positions_px[0] - g.truth[0])).norm(), 0.0, 0.01) << i;
  }
}

TEST(LoopMisclosure, AWrongPairNothingReplacesIsDroppedAndNamed) {
  Grid3x3 g = MakeGrid();
  const size_t wrong = WrongPair(g);
  g.pairs[wrong].offset_px += Eigen::Vector2d(0.0, 8.0);
  g.pairs[wrong].quality = 0.6;
  const auto research = [](const PairRegistration& pair, const Eigen::Vector2d&, const Eigen::Vector2d&) {
    PairRegistration none = pair;
    none.accepted = false;
    return none;
  };
  const LoopCheck check = CheckPairsAgainstLoops(g.stage, 10.0, g.pairs, research);
  ASSERT_EQ(check.overruled.size(), 1u);
  EXPECT_EQ(check.overruled[0].pair, static_cast<int>(wrong));
  EXPECT_FALSE(check.overruled[0].replaced);
  EXPECT_FALSE(g.pairs[wrong].accepted);
  EXPECT_NE(g.pairs[wrong].rejection.find("overruled by the loops"), std::string::npos);
  EXPECT_NE(check.overruled[0].Text().find("dropped"), std::string::npos);
}

TEST(LoopMisclosure, MisclosuresBeyondThePairsPrecisionScaleIt) {
  // Every pair off by a random 0.1 px where it claims 0.01 px: no pair is overruled (all sub-pixel), and the Birge
  // ratio says what the loops show, about ten times what the pairs claim.
  Grid3x3 g = MakeGrid();
  unsigned state = 7;
  const auto noise = [&] {
    state = state * 1103515245u + 12345u;
    return (static_cast<int>((state >> 8) % 2001) - 1000) / 1000.0 * 0.1 * std::sqrt(3.0);  // uniform, sd 0.1
  };
  for (auto& pair : g.pairs) pair.offset_px += Eigen::Vector2d(noise(), noise());
  const LoopCheck check = CheckPairsAgainstLoops(
      g.stage, 10.0, g.pairs, [](const PairRegistration& pair, const Eigen::Vector2d&, const Eigen::Vector2d&) { return pair; });
  EXPECT_TRUE(check.overruled.empty());
  // 12 pairs, 8 tiles relative to the first: 8 degrees of freedom; the ratio's own spread is ~25 % then.
  EXPECT_NEAR(check.dof, 8.0, 0.01);
  EXPECT_GT(check.birge_ratio, 5.0);
  EXPECT_LT(check.birge_ratio, 16.0);
  // The solve scales every pair's uncertainty by it (and by Student's sqrt(dof / (dof - 2)), UncertaintyScale); the
  // pairs keep their own claims.
  // The degrees of freedom as the count of the loops' redundancy (the stage prior's pull takes a hair off it).
  EXPECT_DOUBLE_EQ(check.uncertainty_scale, check.birge_ratio * std::sqrt(8.0 / 6.0));
  // A ring of 8 tiles around a blank one read 2.0000002 degrees of freedom, and the t factor scaled every pair's u by
  // 1400 (issue 42): 2 it is, and the pairs are only ever scaled up, by R above 1.
  EXPECT_DOUBLE_EQ(UncertaintyScale(0.46, 2.0000002), 1.0);
  EXPECT_DOUBLE_EQ(UncertaintyScale(1.5, 1.9999998), 1.5);
  EXPECT_DOUBLE_EQ(g.pairs[0].information(0, 0), 1e4);
}


TEST(LoopMisclosure, ScaledUncertaintiesGiveStandardisedErrorsOfUnitRmsOnFewLoops) {
  // Every pair off by Gaussian noise of 0.1 px where it claims 0.01 px, on the 3 x 3 grid (8 degrees of freedom),
  // 600 times: the positions' errors over their uncertainties scaled by the loops have an rms of 1. The Birge ratio
  // alone, estimated from 8 misclosures, leaves Student's t with 8 degrees of freedom, whose rms is sqrt(8 / 6) =
  // 1.15. (The rms of 600 grids' 16 errors is known to about 2 %: the grids' ratios are independent, their tiles'
  // errors within a grid are not.)
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.1);
  double sum = 0.0, sum_birge_only = 0.0;
  int count = 0;
  for (int run = 0; run < 600; ++run) {
    Grid3x3 g = MakeGrid();
    for (auto& pair : g.pairs) pair.offset_px += Eigen::Vector2d(noise(rng), noise(rng));
    const LoopCheck check = CheckPairsAgainstLoops(
        g.stage, 1e3, g.pairs, [](const PairRegistration& pair, const Eigen::Vector2d&, const Eigen::Vector2d&) { return pair; });
    ASSERT_TRUE(check.overruled.empty());
    std::vector<PairRegistration> scaled = g.pairs;
    for (auto& pair : scaled) pair.information /= check.uncertainty_scale * check.uncertainty_scale;
    const TilePositions p = SolveTilePositions(g.stage, scaled, 1e3);
    const double t_rms = std::sqrt(check.dof / (check.dof - 2.0));
    for (size_t i = 1; i < g.truth.size(); ++i) {
      const Eigen::Vector2d e = (p.positions_px[i] - p.positions_px[0]) - (g.truth[i] - g.truth[0]);
      for (int k = 0; k < 2; ++k) {
        const double z = e(k) / p.sigma_px[i](k);
        sum += z * z, sum_birge_only += z * z * t_rms * t_rms, ++count;
      }
    }
  }
  const double rms = std::sqrt(sum / count), rms_birge_only = std::sqrt(sum_birge_only / count);
  std::printf("standardised errors: rms %.3f scaled by the loops, %.3f by the Birge ratio alone\n", rms, rms_birge_only);
  EXPECT_NEAR(rms, 1.0, 0.06);
  EXPECT_GT(rms_birge_only, 1.08);
  // Too few loops to trust the ratio: never scaled down.
  EXPECT_DOUBLE_EQ(UncertaintyScale(0.3, 2.0), 1.0);
  EXPECT_DOUBLE_EQ(UncertaintyScale(3.0, 1.0), 3.0);
}

}  // namespace
}  // namespace fvm::imaging
