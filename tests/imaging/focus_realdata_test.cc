// fvm focus on a real focus stack (../shared/realdata/focus/pcb: 7 colour JPEG frames of a circuit board under a
// macro lens that breathes, no z values; expected.jpg is the all-in-focus image of the open tool focus-stack).
// Skips where ../shared is absent.
//
// What is checked, with no height truth: the all-in-focus image is at least as sharp as focus-stack's (mean
// Tenengrad, computed here by its own loop, within 5 %), and the depth map shows the board as one smooth plane
// with the USB connector standing in front of it. The regions were read off the pictures (2048 x 1536 px).

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "imaging/io/focus_stack_files.h"
#include "imaging/io/focus_stack_io.h"

namespace fvm {
namespace {

const std::filesystem::path kStack = std::filesystem::path(FVM_REALDATA_DIR) / "focus" / "pcb";

// Mean of Gx^2 + Gy^2 of the 3 x 3 Sobel operator over the grey (mean of the channels) image, leaving out a
// border of `border` px (the aligned frames repeat their edges there).
double MeanTenengrad(const imaging::StackImage& image, int border) {
  const auto& px = std::get<std::vector<std::uint8_t>>(image.pixels);
  const int w = image.width, h = image.height, c = image.channels;
  std::vector<double> grey(std::size_t(w) * std::size_t(h));
  for (std::size_t i = 0; i < grey.size(); ++i) {
    double sum = 0.0;
    for (int k = 0; k < c; ++k) sum += px[i * std::size_t(c) + std::size_t(k)];
    grey[i] = sum / c;
  }
  const auto g = [&](int x, int y) { return grey[std::size_t(y) * std::size_t(w) + std::size_t(x)]; };
  double total = 0.0;
  std::size_t n = 0;
  for (int y = border; y < h - border; ++y) {
    for (int x = border; x < w - border; ++x) {
      const double gx = (g(x + 1, y - 1) + 2 * g(x + 1, y) + g(x + 1, y + 1)) - (g(x - 1, y - 1) + 2 * g(x - 1, y) + g(x - 1, y + 1));
      const double gy = (g(x - 1, y + 1) + 2 * g(x, y + 1) + g(x + 1, y + 1)) - (g(x - 1, y - 1) + 2 * g(x, y - 1) + g(x + 1, y - 1));
      total += gx * gx + gy * gy;
      ++n;
    }
  }
  return total / double(n);
}

TEST(FocusRealData, PcbAllInFocusAndDepth) {
  if (!std::filesystem::exists(kStack / "pcb_001.jpg")) GTEST_SKIP() << kStack << " is absent";
  std::vector<std::filesystem::path> frames;
  for (int k = 1; k <= 7; ++k) {
    std::string name = "pcb_00";  // appended, not `"pcb_00" + ...`: GCC 12 warns falsely (-Wrestrict) on that
    name += std::to_string(k);
    name += ".jpg";
    frames.push_back(kStack / name);
  }
  imaging::FocusStackFilesOptions o;
  o.align = true;
  o.colour = true;
  o.focus.min_quality = 1.5;  // 7 images: a peak over the mean measure cannot exceed 7
  o.focus.keep_end_peaks = true;
  const imaging::FocusStackFilesResult r =
      imaging::ReconstructFocusStackFiles(imaging::ResolveFocusStack(frames, std::nullopt), o);
  ASSERT_EQ(r.alignment.size(), 7u);
  // The lens breathes: the last frame is magnified against the first by a few per cent.
  const double scale = std::sqrt(std::abs(r.alignment[6][0] * r.alignment[6][4] - r.alignment[6][1] * r.alignment[6][3]));
  std::printf("frame 7 against frame 1: scale %.4f, shift %.1f, %.1f px\n", scale, r.alignment[6][2], r.alignment[6][5]);
  EXPECT_GT(std::abs(scale - 1.0), 0.005);
  EXPECT_LT(std::abs(scale - 1.0), 0.1);

  const imaging::StackImage ours = imaging::AllInFocusImage(r.focus, true);
  const imaging::StackImage theirs = imaging::ReadStackColour(kStack / "expected.jpg");
  ASSERT_EQ(ours.width, theirs.width);
  const double t_ours = MeanTenengrad(ours, 64), t_theirs = MeanTenengrad(theirs, 64);
  std::printf("mean Tenengrad: fvm %.1f, focus-stack %.1f, ratio %.3f\n", t_ours, t_theirs, t_ours / t_theirs);
  EXPECT_GE(t_ours, 0.95 * t_theirs);

  // The board: a plane in slice units over its bare part (soldermask, print and pads, all on the board).
  const imaging::HeightMap& z = r.focus.height;
  std::vector<Eigen::Vector3d> board;
  for (int y = 620; y < 940; y += 2) {
    for (int x = 420; x < 1160; x += 2) {
      if (std::isfinite(z.at(x, y))) board.emplace_back(x, y, z.at(x, y));
    }
  }
  ASSERT_GT(board.size(), 30000u);
  Eigen::MatrixXd a(board.size(), 3);
  Eigen::VectorXd b(board.size());
  for (std::size_t i = 0; i < board.size(); ++i) a.row(Eigen::Index(i)) << 1.0, board[i].x(), board[i].y(), b(Eigen::Index(i)) = board[i].z();
  const Eigen::Vector3d plane = a.colPivHouseholderQr().solve(b);
  std::vector<double> residual(board.size());
  for (std::size_t i = 0; i < board.size(); ++i) residual[i] = std::abs(b(Eigen::Index(i)) - a.row(Eigen::Index(i)).dot(plane));
  std::nth_element(residual.begin(), residual.begin() + residual.size() / 2, residual.end());
  const double mad = residual[residual.size() / 2];
  const std::size_t within = std::count_if(residual.begin(), residual.end(), [](double d) { return d < 1.0; });
  std::printf("board plane: %.3f slices per 1000 px down the image, median |residual| %.3f slice, %.1f %% within 1 slice\n",
              plane(2) * 1000, mad, 100.0 * double(within) / double(residual.size()));
  EXPECT_LT(mad, 0.3);
  EXPECT_GT(double(within), 0.9 * double(residual.size()));
  // The board recedes up the image (frame 1 is focused on its front edge, frame 7 behind it).
  EXPECT_LT(plane(2), 0.0);

  // The USB connector's top stands in front of the board plane there.
  std::vector<double> in_front;
  for (int y = 1020; y < 1120; y += 2) {
    for (int x = 450; x < 1100; x += 2) {
      if (std::isfinite(z.at(x, y))) in_front.push_back(plane(0) + plane(1) * x + plane(2) * y - z.at(x, y));
    }
  }
  ASSERT_GT(in_front.size(), 5000u);
  std::nth_element(in_front.begin(), in_front.begin() + in_front.size() / 2, in_front.end());
  std::printf("USB connector: median %.2f slices in front of the board plane\n", in_front[in_front.size() / 2]);
  EXPECT_GT(in_front[in_front.size() / 2], 1.0);
}

}  // namespace
}  // namespace fvm
