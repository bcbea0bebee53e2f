// The slope beside a sharp bend (imaging/focus_slope_beside_bends.h) on a map whose answer is known: a level face
// (0.01 step per px) meeting a wall (0.45 step per px, a calotte's rim at 24 deg) along a straight bend, with noise
// on the heights, both smoothed over 2 px and differentiated as the focus code does. Beside the bend the smoothed
// slope mixes the two sides; the slope read beside it must be each side's own.

#include "imaging/focus_slope_beside_bends.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace fvm {
namespace {

constexpr int kBendMapPx = 160;
constexpr double kBendStepMm = 1e-3, kBendAt = 80.0;
constexpr double kLevelSlope = 0.01 * kBendStepMm, kWallSlope = 0.45 * kBendStepMm;  // mm per px along x

struct BendScene {
  std::vector<float> smooth, slope_x, slope_y, valid, beside_x, beside_y;
};

// Heights rising along x at the level slope up to the bend, then at the wall's beyond it (plus a small slope along y),
// with noise of 0.05 step; their Gaussian mean over 2 px (each row and column, reflected at the edges) and its central
// differences as the slope.
BendScene BentFace(bool bend, double bend_at = kBendAt) {
  const std::size_t n = std::size_t(kBendMapPx) * kBendMapPx;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05 * kBendStepMm);
  std::vector<double> z(n), tmp(n);
  for (int r = 0; r < kBendMapPx; ++r) {
    for (int c = 0; c < kBendMapPx; ++c) {
      const double beyond = bend ? std::max(c - bend_at, 0.0) : 0.0;
      z[std::size_t(r) * kBendMapPx + std::size_t(c)] =
          kLevelSlope * c + (kWallSlope - kLevelSlope) * beyond + 0.002 * kBendStepMm * r + noise(rng);
    }
  }
  std::vector<double> taps(17);
  double sum = 0.0;
  for (int k = -8; k <= 8; ++k) sum += taps[std::size_t(k + 8)] = std::exp(-k * k / 8.0);
  for (double& t : taps) t /= sum;
  const auto reflect = [](int i) { return i < 0 ? -i - 1 : i >= kBendMapPx ? 2 * kBendMapPx - i - 1 : i; };
  for (int pass = 0; pass < 2; ++pass) {
    for (int r = 0; r < kBendMapPx; ++r) {
      for (int c = 0; c < kBendMapPx; ++c) {
        double s = 0.0;
        for (int k = -8; k <= 8; ++k) {
          const std::size_t i = pass == 0 ? std::size_t(r) * kBendMapPx + std::size_t(reflect(c + k))
                                          : std::size_t(reflect(r + k)) * kBendMapPx + std::size_t(c);
          s += taps[std::size_t(k + 8)] * (pass == 0 ? z[i] : tmp[i]);
        }
        (pass == 0 ? tmp : z)[std::size_t(r) * kBendMapPx + std::size_t(c)] = s;
      }
    }
  }
  BendScene s{std::vector<float>(n),       std::vector<float>(n), std::vector<float>(n),
              std::vector<float>(n, 1.0f), std::vector<float>(n), std::vector<float>(n)};
  for (int r = 0; r < kBendMapPx; ++r) {
    for (int c = 0; c < kBendMapPx; ++c) {
      const std::size_t i = std::size_t(r) * kBendMapPx + std::size_t(c);
      s.smooth[i] = float(z[i]);
      s.slope_x[i] = float((z[std::size_t(r) * kBendMapPx + std::size_t(reflect(c + 1))] -
                            z[std::size_t(r) * kBendMapPx + std::size_t(reflect(c - 1))]) /
                           2.0);
      s.slope_y[i] = float((z[std::size_t(reflect(r + 1)) * kBendMapPx + std::size_t(c)] -
                            z[std::size_t(reflect(r - 1)) * kBendMapPx + std::size_t(c)]) /
                           2.0);
    }
  }
  imaging::MapPool pool(kBendMapPx, kBendMapPx, true);
  imaging::SlopeBesideBends(pool, s.smooth.data(), s.slope_x.data(), s.slope_y.data(), s.valid.data(), kBendStepMm,
                            1.0, s.beside_x.data(), s.beside_y.data());
  return s;
}

TEST(FocusSlopeBesideBends, ReadsEachSidesOwnSlopeBesideABend) {
  const BendScene s = BentFace(true);
  for (int r = 20; r < kBendMapPx - 20; ++r) {
    for (int offset : {-7, -5, -3, 3, 5, 7}) {  // px beyond the bend: the level face before it, the wall after
      const int c = int(kBendAt) + offset;
      const std::size_t i = std::size_t(r) * kBendMapPx + std::size_t(c);
      const double own = offset < 0 ? kLevelSlope : kWallSlope;
      // The smoothed slope 3 px from the bend is off by more than the tolerance below (so the test can fail)...
      if (std::abs(offset) == 3) {
        EXPECT_GT(std::abs(s.slope_x[i] - own), 0.05 * (kWallSlope - kLevelSlope)) << r << "," << c;
      }
      // ... the slope read beside it is the side's own within the noise's (0.02 step per px on a 2 px mean).
      EXPECT_NEAR(s.beside_x[i], own, 0.02 * kBendStepMm) << r << "," << c;
      EXPECT_NEAR(s.beside_y[i], 0.002 * kBendStepMm, 0.02 * kBendStepMm) << r << "," << c;
    }
  }
}

// Far from a bend, and on a map without one, the slope is the map's own: untouched at most points, and where a ridge
// of the noise passes the cut, that of a point nearby on the same plane (within the noise of the slope). Not within
// 20 px of the map's edges, where the reflected heights bend the smoothed slope (a bend the function may mend).
void ExpectOwnSlope(const BendScene& s, int first_column, int end_column) {
  int same = 0, points = 0;
  for (int r = 20; r < kBendMapPx - 20; ++r) {
    for (int c = first_column; c < end_column; ++c) {
      const std::size_t i = std::size_t(r) * kBendMapPx + std::size_t(c);
      EXPECT_NEAR(s.beside_x[i], s.slope_x[i], 0.02 * kBendStepMm) << r << "," << c;
      EXPECT_NEAR(s.beside_y[i], s.slope_y[i], 0.02 * kBendStepMm) << r << "," << c;
      same += s.beside_x[i] == s.slope_x[i] && s.beside_y[i] == s.slope_y[i];
      ++points;
    }
  }
  EXPECT_GT(same, 0.9 * points) << first_column << ".." << end_column;
}

TEST(FocusSlopeBesideBends, KeepsTheSlopeFarFromABendAndWithoutOne) {
  const BendScene bent = BentFace(true);
  ExpectOwnSlope(bent, 20, int(kBendAt) - 20);
  ExpectOwnSlope(bent, int(kBendAt) + 20, kBendMapPx - 20);
  ExpectOwnSlope(BentFace(false), 20, kBendMapPx - 20);
}

// A bend 6 px from the map's edge leaves the wall beyond it no point out of the ridge's reach: the nearest such point
// lies across the bend, its plane misses the wall's heights, and the wall keeps the map's own slope.
TEST(FocusSlopeBesideBends, KeepsTheSlopeWhereTheOwnSideIsCutOff) {
  const double bend_at = kBendMapPx - 7.0;
  const BendScene s = BentFace(true, bend_at);
  for (int r = 20; r < kBendMapPx - 20; ++r) {
    for (int c = int(bend_at) + 2; c < kBendMapPx; ++c) {
      const std::size_t i = std::size_t(r) * kBendMapPx + std::size_t(c);
      EXPECT_EQ(s.beside_x[i], s.slope_x[i]) << r << "," << c;
    }
  }
}

}  // namespace
}  // namespace fvm
