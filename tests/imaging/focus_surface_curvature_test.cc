// The surface's curvature at a large scale (imaging/focus_surface_curvature.h) on a synthetic Laplacian whose
// answer is known: a disk of constant curvature in a plane, its rim a sharp bend whose ridge the bends' mask flags
// only in half its sectors, noise of twice the curvature on every point, and holes holding garbage.

#include "imaging/focus_surface_curvature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace fvm {
namespace {

constexpr int kCurvatureMapPx = 256;
constexpr double kDiskCentre = 128.0, kDiskRim = 75.0;
constexpr double kDiskCurvature = 5e-6;  // mm per px^2: a sphere of 0.4 mm radius in 1 um pixels

struct CurvatureScene {
  std::vector<float> laplacian, weight, bends, curvature;
};

CurvatureScene CurvedDisk(bool flag_every_sector) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 2.0 * kDiskCurvature);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const std::size_t n = std::size_t(kCurvatureMapPx) * kCurvatureMapPx;
  CurvatureScene s{std::vector<float>(n), std::vector<float>(n), std::vector<float>(n), std::vector<float>(n)};
  for (int r = 0; r < kCurvatureMapPx; ++r) {
    for (int c = 0; c < kCurvatureMapPx; ++c) {
      const std::size_t i = std::size_t(r) * kCurvatureMapPx + std::size_t(c);
      const double d = std::hypot(r - kDiskCentre, c - kDiskCentre) - kDiskRim;  // px beyond the rim
      const double angle = std::atan2(r - kDiskCentre, c - kDiskCentre) + std::numbers::pi;
      const bool flagged_sector = flag_every_sector || int(angle / (std::numbers::pi / 6)) % 2 == 0;
      const bool hole = uniform(rng) < 0.3;
      s.weight[i] = hole ? 0.0f : 1.0f;
      s.bends[i] = std::abs(d) <= 1.0 && flagged_sector && !hole ? 1.0f : 0.0f;
      // The rim's ridge (a bend of the slope, negative as a calotte's rim whose slope falls by 0.45 px per px: -90
      // times the curvature summed across it): 15 times the curvature on the bend, shoulders of 6 times it out to
      // 5 px either side that no bend test flags.
      const double ridge = std::abs(d) <= 1.0 ? -15 * kDiskCurvature : std::abs(d) <= 5.0 ? -6 * kDiskCurvature : 0.0;
      s.laplacian[i] = hole ? 1.0f : float((d < 0.0 ? kDiskCurvature : 0.0) + ridge + noise(rng));
    }
  }
  imaging::MapPool pool(kCurvatureMapPx, kCurvatureMapPx, true);
  imaging::SurfaceCurvature(pool, s.laplacian.data(), s.weight.data(), s.bends.data(), s.curvature.data());
  return s;
}

TEST(FocusSurfaceCurvature, HoldsEachSidesCurvatureAndNoneNearTheRidge) {
  const CurvatureScene s = CurvedDisk(false);
  int inside = 0, outside = 0, near = 0, inside_known = 0, outside_known = 0;
  for (int r = 8; r < kCurvatureMapPx - 8; ++r) {
    for (int c = 8; c < kCurvatureMapPx - 8; ++c) {
      const float k = s.curvature[std::size_t(r) * kCurvatureMapPx + std::size_t(c)];
      const double d = std::hypot(r - kDiskCentre, c - kDiskCentre) - kDiskRim;
      if (std::abs(d) <= 6.0) {  // on the ridge, flagged or not: unknown
        EXPECT_TRUE(std::isnan(k)) << r << "," << c;
        ++near;
      } else if (d < -30.0) {  // the disk's curvature, known nearly everywhere
        inside_known += std::isfinite(k);
        if (std::isfinite(k)) {
          EXPECT_NEAR(k, kDiskCurvature, 0.2 * kDiskCurvature) << r << "," << c;
        }
        ++inside;
      } else if (d > 30.0) {
        outside_known += std::isfinite(k);
        if (std::isfinite(k)) {
          EXPECT_NEAR(k, 0.0, 0.2 * kDiskCurvature) << r << "," << c;
        }
        ++outside;
      } else if (std::isfinite(k)) {  // beside the ridge: the side's own curvature, a little of the other's in it
        EXPECT_GT(k, (d < 0.0 ? 0.7 : -0.2) * kDiskCurvature) << r << "," << c;
        EXPECT_LT(k, (d < 0.0 ? 1.2 : 0.3) * kDiskCurvature) << r << "," << c;
      }
    }
  }
  EXPECT_GT(near, 4000);
  EXPECT_GT(inside, 5000);
  EXPECT_GT(outside, 10000);
  EXPECT_GT(inside_known, 0.95 * inside);
  EXPECT_GT(outside_known, 0.95 * outside);
}

TEST(FocusSurfaceCurvature, TheRidgeTestFindsWhatTheBendsMaskMissed) {
  // The same disk with its whole rim flagged: the curvatures agree where both are known (the ridge test found
  // the unflagged sectors above).
  const CurvatureScene half = CurvedDisk(false), whole = CurvedDisk(true);
  int both = 0;
  for (std::size_t i = 0; i < half.curvature.size(); ++i) {
    if (!std::isfinite(half.curvature[i]) || !std::isfinite(whole.curvature[i])) continue;
    EXPECT_NEAR(half.curvature[i], whole.curvature[i], 0.15 * kDiskCurvature);  // 3 times the means' noise
    ++both;
  }
  EXPECT_GT(both, 30000);
}

TEST(FocusSurfaceCurvature, UnknownWhereNoPointHasWeight) {
  constexpr int kCurvatureRows = 200;
  const std::size_t n = std::size_t(kCurvatureRows) * kCurvatureMapPx;
  std::vector<float> laplacian(n, 1e-6f), weight(n, 0.0f), bends(n, 0.0f), curvature(n, 0.0f);
  for (std::size_t i = 0; i < n / 4; ++i) weight[i] = 1.0f;  // the first 50 rows only
  imaging::MapPool pool(kCurvatureMapPx, kCurvatureRows, false);
  imaging::SurfaceCurvature(pool, laplacian.data(), weight.data(), bends.data(), curvature.data());
  EXPECT_NEAR(curvature[std::size_t(25) * kCurvatureMapPx + 100], 1e-6f, 1e-9f);
  EXPECT_TRUE(std::isnan(curvature[std::size_t(190) * kCurvatureMapPx + 100]));  // 140 px from any weight
}

}  // namespace
}  // namespace fvm
