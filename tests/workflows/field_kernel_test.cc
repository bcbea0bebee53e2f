// A correspondence follows the field averaged over its matching window (imaging::FieldKernel), not the field at its
// centre: the average of a polynomial field over a window is exact from the window's moments, and on
// ../shared/bench's independent scan generator (skipped where it or numpy is absent) the steps the correspondences
// give with the true field held match scangen's true shifts only when they are read through that kernel; so do the
// steps registered on tiles undistorted by that field (UndistortTile).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "imaging/field_distortion.h"
#include "imaging/io/tile_image.h"
#include "imaging/overlap_correspondences.h"
#include "imaging/tile_pair_registration.h"
#include "tests/support/test_support.h"

namespace fvm::imaging {
namespace {

const std::filesystem::path kScangen = std::filesystem::path(FVM_BENCH_DIR) / "scangen.py";

FieldDistortion RandomField(int width, int height, int order, unsigned seed) {
  FieldDistortion f;
  f.width_px = width, f.height_px = height, f.order = order;
  f.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(FieldDistortionTermNames(order).size()));
  for (Eigen::Index t = 0; t < f.coefficients.size(); ++t) f.coefficients(t) = std::sin(1.7 * (t + 1) + seed) * 3.0;
  return f;
}

// The kernel's closed form against the field averaged pixel by pixel over the window (uniform) and a discrete
// stand-in for the smoothing (offsets -1, 0, 1 weighing 1/2 each at +-1: variance 1, fourth moment 1, sixth 1).
TEST(FieldKernel, AveragesAPolynomialFieldOverTheWindowExactly) {
  const int half = 7;
  const FieldKernel window = [&] {
    double m2 = 0.0, m4 = 0.0, m6 = 0.0;
    for (int v = -half; v <= half; ++v) m2 += std::pow(v, 2), m4 += std::pow(v, 4), m6 += std::pow(v, 6);
    const double n = 2 * half + 1;
    return FieldKernel{m2 / n, m4 / n, m6 / n};
  }();
  for (int order : {3, 6}) {
    const FieldDistortion field = RandomField(512, 384, order, static_cast<unsigned>(order));
    for (const Eigen::Vector2d& u : {Eigen::Vector2d(40.0, 300.5), Eigen::Vector2d(470.25, 12.0)}) {
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      double weights = 0.0;
      for (int vy = -half; vy <= half; ++vy) {
        for (int vx = -half; vx <= half; ++vx) {
          mean += field.Displacement(u + Eigen::Vector2d(vx, vy)), weights += 1.0;
        }
      }
      mean /= weights;
      EXPECT_LT((field.Displacement(u, window) - mean).norm(), 1e-12) << "order " << order;
      Eigen::Matrix<double, 2, Eigen::Dynamic> basis_mean = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, field.coefficients.size());
      for (int vy = -half; vy <= half; ++vy) {
        for (int vx = -half; vx <= half; ++vx) basis_mean += field.Basis(u + Eigen::Vector2d(vx, vy)) / weights;
      }
      EXPECT_LT((field.Basis(u, window) - basis_mean).norm(), 1e-12);
      // A window too is a sum of two independent offsets: the kernel of the window and a 3-point smoothing.
      Eigen::Vector2d smoothed = Eigen::Vector2d::Zero();
      for (int sy : {-1, 1}) {
        for (int sx : {-1, 1}) {
          for (int vy = -half; vy <= half; ++vy) {
            for (int vx = -half; vx <= half; ++vx) smoothed += field.Displacement(u + Eigen::Vector2d(vx + sx, vy + sy));
          }
        }
      }
      smoothed /= 4.0 * weights;
      const FieldKernel both{window.m2 + 1.0, window.m4 + 6.0 * window.m2 + 1.0,
                             window.m6 + 15.0 * window.m4 + 15.0 * window.m2 + 1.0};
      EXPECT_LT((field.Displacement(u, both) - smoothed).norm(), 1e-12);
    }
  }
  // The default kernel is the pixel itself.
  const FieldDistortion field = RandomField(256, 256, 4, 1);
  EXPECT_EQ(field.Displacement(Eigen::Vector2d(3.0, 200.0)), field.Displacement(Eigen::Vector2d(3.0, 200.0), {}));
}

// scangen's pairs (512 px tiles, 20 % overlap: 410 px steps; D = 3 px of radial field at the middle of the edges,
// k1 = 3 in fvm's terms) matched with the true field as the guess, each step the mean over its correspondences of
// u_a + d(u_a) - u_b - d(u_b), against the true shift in truth.json along the step. Read with d at the windows'
// centres, the steps were 0.0060 px short (-0.0041 for D = 2, +0.0039 for D = -2: 4.7 ppm of the step per px of
// D, the cubic field's curvature averaged over the 15 px window, a linear field the overlaps cannot tell from the
// step); read with d averaged over the window, within 0.0003 px of the truth on 17-pair scans of D = +-2, +-3.
// The mean of 15 pairs scatters by 0.0006 px (one pair's step by 0.0024: measured on the same scans), so 0.002 px
// bounds it at over 3 standard deviations and the old reading fails by 7. The same pairs registered on their tiles
// undistorted by the true field (what a pair the field fit cannot place gets, and fvm stitch's second registration):
// +0.0033 px a step when the undistortion was cubic, its map bilinear between knots and its edges a ring of NaN;
// +0.0001 now, whose mean over 15 pairs scatters by 0.0005 px (one pair's by 0.0019): bounded at 0.0015 px.
TEST(FieldKernel, StepsOfTheIndependentScanGeneratorMatchItsTrueShifts) {
  if (!std::filesystem::exists(kScangen) || std::system("/usr/bin/python3 -c 'import numpy' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "../shared/bench/scangen.py or numpy absent";
  }
  const fvm::testing::TempDir dir;
  const std::string command =
      fmt::format("/usr/bin/python3 '{}' '{}' --seed 2 --length-mm 6 --screw-um 0 --distortion-px 3 >/dev/null",
                  kScangen.string(), dir.path().string());
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  nlohmann::json truth;
  std::ifstream(dir.path() / "truth.json") >> truth;
  FieldDistortion field = RandomField(512, 512, 3, 0);
  field.coefficients.setZero();
  field.coefficients(static_cast<Eigen::Index>(
      std::find(FieldDistortionTermNames(3).begin(), FieldDistortionTermNames(3).end(), "k1") -
      FieldDistortionTermNames(3).begin())) = 3.0;
  double windowed = 0.0, centred = 0.0, undistorted = 0.0;
  int pairs = 0;
  for (const nlohmann::json& p : truth["pairs"]) {
    const TileImage a = ReadTileImage(dir.path() / p["a"].get<std::string>());
    const TileImage b = ReadTileImage(dir.path() / p["b"].get<std::string>());
    const Eigen::Vector2d shift(p["dx_px"].get<double>(), p["dy_px"].get<double>());
    const PairCorrespondences c = MatchOverlap(a, b, 0, 1, shift, field);
    ASSERT_GT(c.a_px.size(), 500u);
    Eigen::Vector2d with_kernel = Eigen::Vector2d::Zero(), at_centre = Eigen::Vector2d::Zero();
    for (size_t m = 0; m < c.a_px.size(); ++m) {
      const Eigen::Vector2d du = c.a_px[m] - c.b_px[m];
      with_kernel += du + field.Displacement(c.a_px[m], c.kernel) - field.Displacement(c.b_px[m], c.kernel);
      at_centre += du + field.Displacement(c.a_px[m]) - field.Displacement(c.b_px[m]);
    }
    const int along = std::abs(shift.x()) > std::abs(shift.y()) ? 0 : 1;
    windowed += with_kernel(along) / static_cast<double>(c.a_px.size()) - shift(along);
    centred += at_centre(along) / static_cast<double>(c.a_px.size()) - shift(along);
    const PairRegistration again = RegisterPair(UndistortTile(a, field), UndistortTile(b, field), shift, {});
    ASSERT_TRUE(again.accepted) << again.rejection;
    undistorted += again.offset_px(along) - shift(along);
    ++pairs;
  }
  ASSERT_EQ(pairs, 15);
  windowed /= pairs, centred /= pairs, undistorted /= pairs;
  EXPECT_LT(std::abs(windowed), 0.002) << "mean step error with the window's kernel (px)";
  EXPECT_LT(centred, -0.004) << "mean step error at the windows' centres (px): the bias the kernel removes";
  EXPECT_LT(std::abs(undistorted), 0.0015) << "mean step error registered on the undistorted tiles (px)";
}

}  // namespace
}  // namespace fvm::imaging
