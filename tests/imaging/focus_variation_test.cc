// Focus variation on stacks rendered from known surfaces (artefacts/focus_stack_render.h): the height error
// against the truth, for every focus measure, and the errors a bad stack must raise.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "artefacts/simulation/calotte_surface.h"
#include "artefacts/simulation/focus_stack_render.h"
#include "imaging/focus_variation.h"
#include "tests/support/test_support.h"

namespace fvm {
namespace {

using imaging::FocusMeasure;

using testing::ExpectInputError;

struct HeightError {
  double rms_mm = 0.0, max_mm = 0.0;
  std::size_t compared = 0, truth_points = 0;
};

// Over the points valid in both, leaving out a border of `border` px where the window reflects at the edge.
HeightError Compare(const imaging::HeightMap& result, const imaging::HeightMap& truth, int border) {
  HeightError e;
  double sum = 0.0;
  for (int y = border; y < truth.size_y - border; ++y) {
    for (int x = border; x < truth.size_x - border; ++x) {
      if (!std::isfinite(truth.at(x, y))) continue;
      ++e.truth_points;
      if (!std::isfinite(result.at(x, y))) continue;
      const double d = double(result.at(x, y)) - truth.at(x, y);
      sum += d * d;
      e.max_mm = std::max(e.max_mm, std::abs(d));
      ++e.compared;
    }
  }
  e.rms_mm = e.compared > 0 ? std::sqrt(sum / double(e.compared)) : 0.0;
  return e;
}

constexpr double kStepMm = 0.001;  // 1 um between images; the render blurs by 1 px sigma per um of defocus

// A plane rising 16 um along x and 6 um along y, inside a stack from 0 to 40 um.
imaging::HeightMap Plane() { return artefacts::TiltedPlane(160, 120, 0.001, 0.012, 0.1, 0.05); }

artefacts::RenderedFocusStack Render(const imaging::HeightMap& surface, double z_first, int count,
                                     artefacts::StackPixelType type = artefacts::StackPixelType::kUint8) {
  artefacts::FocusStackRenderOptions o;
  o.z_mm = artefacts::EvenZSteps(z_first, kStepMm, count);
  o.type = type;
  if (type == artefacts::StackPixelType::kUint16) o.level *= 256, o.contrast *= 256, o.noise *= 256;
  o.seed = 3;
  return artefacts::RenderFocusStack(surface, o);
}

class FocusMeasureTest : public ::testing::TestWithParam<FocusMeasure> {};

TEST_P(FocusMeasureTest, TiltedPlaneWithinTenthOfStep) {
  const imaging::HeightMap truth = Plane();
  const artefacts::RenderedFocusStack stack = Render(truth, 0.0, 41);
  imaging::FocusVariationOptions o;
  o.measure = GetParam();
  const imaging::FocusResult result = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  const HeightError e = Compare(result.height, truth, o.window);
  std::printf("%s plane: rms %.3f um, max %.3f um, %zu of %zu points\n",
              imaging::FocusMeasureName(o.measure).c_str(), e.rms_mm * 1e3, e.max_mm * 1e3, e.compared,
              e.truth_points);
  EXPECT_EQ(e.compared, e.truth_points);
  EXPECT_LT(e.rms_mm, 0.1 * kStepMm);
}

INSTANTIATE_TEST_SUITE_P(AllMeasures, FocusMeasureTest,
                         ::testing::Values(FocusMeasure::kModifiedLaplacian, FocusMeasure::kTenengrad,
                                           FocusMeasure::kVariance),
                         [](const auto& info) { return imaging::FocusMeasureName(info.param); });

TEST(FocusVariation, ShallowCalotte) {
  artefacts::CalotteSurfaceOptions co;
  co.dx_mm = co.dy_mm = 0.002;
  co.margin_mm = 0.04;
  co.depth_mm = 0.02;
  const artefacts::CalotteSurface surface = artefacts::RenderCalotteSurface(artefacts::SingleCalotte(0.3), co);
  const artefacts::RenderedFocusStack stack = Render(surface.map, -0.026, 33);
  imaging::FocusVariationOptions o;
  o.dx_mm = co.dx_mm;
  const imaging::FocusResult result = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  const HeightError e = Compare(result.height, surface.map, o.window);
  std::printf("calotte %d x %d: rms %.3f um, max %.3f um, %zu of %zu points\n", surface.map.size_x,
              surface.map.size_y, e.rms_mm * 1e3, e.max_mm * 1e3, e.compared, e.truth_points);
  EXPECT_GT(e.compared, 0.99 * double(e.truth_points));
  EXPECT_LT(e.rms_mm, 0.1 * kStepMm);
}

// Threads change the order of work, never the numbers: the stripes are fixed, not derived from the pool.
TEST(FocusVariation, ParallelMatchesSingleThreadBitForBit) {
  const imaging::HeightMap truth = Plane();
  const artefacts::RenderedFocusStack stack = Render(truth, 0.0, 41);
  imaging::FocusVariationOptions o;
  const imaging::FocusResult parallel = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  o.parallel = false;
  const imaging::FocusResult single = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  ASSERT_EQ(parallel.height.z_mm.size(), single.height.z_mm.size());
  for (std::size_t i = 0; i < single.height.z_mm.size(); ++i) {
    ASSERT_EQ(std::memcmp(&parallel.height.z_mm[i], &single.height.z_mm[i], sizeof(double)), 0) << i;
    ASSERT_EQ(parallel.quality[i], single.quality[i]) << i;
  }
}

// 16-bit and float images of the same scene give the same heights as 8-bit ones to well within the error:
// the measure does not depend on the grey scale, only the quantisation differs.
TEST(FocusVariation, SixteenBitAndFloatImages) {
  const imaging::HeightMap truth = Plane();
  for (auto type : {artefacts::StackPixelType::kUint16, artefacts::StackPixelType::kFloat32}) {
    const artefacts::RenderedFocusStack stack = Render(truth, 0.0, 41, type);
    for (FocusMeasure m : {FocusMeasure::kModifiedLaplacian, FocusMeasure::kVariance}) {
      imaging::FocusVariationOptions o;
      o.measure = m;
      const HeightError e = Compare(imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o).height, truth, 5);
      EXPECT_EQ(e.compared, e.truth_points);
      EXPECT_LT(e.rms_mm, 0.1 * kStepMm) << imaging::FocusMeasureName(m);
    }
  }
}

// The parabola through the measure itself is the cruder fit (a focus curve is closer to a Gaussian), but it
// still beats picking the best image (whose error is uniform over a step: rms step / sqrt(12) = 0.29 step).
TEST(FocusVariation, ParabolicFitAndBestImage) {
  const imaging::HeightMap truth = Plane();
  const artefacts::RenderedFocusStack stack = Render(truth, 0.0, 41);
  imaging::FocusVariationOptions o;
  o.peak_fit = imaging::PeakFit::kParabolic;
  const imaging::FocusResult result = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  const HeightError parabolic = Compare(result.height, truth, o.window);
  imaging::HeightMap best = result.height;
  for (std::size_t i = 0; i < best.z_mm.size(); ++i) best.z_mm[i] = float(stack.z_mm[std::size_t(result.peak_index[i])]);
  const HeightError nearest = Compare(best, truth, o.window);
  std::printf("parabolic rms %.3f um, best image rms %.3f um\n", parabolic.rms_mm * 1e3, nearest.rms_mm * 1e3);
  EXPECT_NEAR(nearest.rms_mm, kStepMm / std::sqrt(12.0), 0.05 * kStepMm);
  EXPECT_LT(parabolic.rms_mm, 0.5 * nearest.rms_mm);
}

// Where the surface is beyond the stack the peak sits on the last image: no height there, not the last z.
// Where the surface has no texture (NaN in the truth renders as grey in every image) the quality is low.
TEST(FocusVariation, PeaksAtTheEndsAndFlatSpotsAreInvalid) {
  imaging::HeightMap truth = Plane();  // 12 .. 34 um
  for (int y = 40; y < 80; ++y) {
    for (int x = 20; x < 50; ++x) truth.at(x, y) = std::numeric_limits<float>::quiet_NaN();
  }
  const artefacts::RenderedFocusStack stack = Render(truth, 0.0, 26);  // 0 .. 25 um
  imaging::FocusVariationOptions o;
  const imaging::FocusResult result = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, o);
  int flat_valid = 0, beyond_valid = 0, inside = 0, inside_valid = 0;
  const int reach = 9;  // the adaptive mode's large window (Gaussian, sigma 2.7 px) reaches 7 px
  for (int y = reach; y < truth.size_y - reach; ++y) {
    for (int x = reach; x < truth.size_x - reach; ++x) {
      const bool valid = std::isfinite(result.height.at(x, y));
      const float t = truth.at(x, y);
      if (x >= 20 + reach && x < 50 - reach && y >= 40 + reach && y < 80 - reach) {
        flat_valid += valid;
        EXPECT_LT(result.quality[std::size_t(y * truth.size_x + x)], o.min_quality);
      } else if (std::isfinite(t) && t > 0.0255) {
        beyond_valid += valid;
      } else if (std::isfinite(t) && t < 0.023) {  // two steps inside the stack's end
        ++inside;
        inside_valid += valid;
      }
    }
  }
  EXPECT_EQ(flat_valid, 0);
  EXPECT_EQ(beyond_valid, 0);
  EXPECT_GT(inside, 1000);
  EXPECT_GT(inside_valid, inside * 99 / 100);
}

imaging::StackImage Grey(int w, int h) {
  imaging::StackImage image;
  image.width = w;
  image.height = h;
  image.pixels = std::vector<std::uint8_t>(std::size_t(w) * std::size_t(h), 100);
  return image;
}

TEST(FocusVariation, BadStacks) {
  const imaging::StackImage a = Grey(32, 24), b = Grey(32, 24), small = Grey(31, 24);
  imaging::FocusVariationOptions o;
  // One image, two images: no peak with a neighbour on either side.
  for (int n : {0, 1, 2}) {
    imaging::FocusAccumulator acc(o);
    for (int k = 0; k < n; ++k) acc.Add(a.View(), 0.001 * k);
    ExpectInputError([&] { (void)acc.Finish(); }, "at least 3");
  }
  {
    imaging::FocusAccumulator acc(o);
    acc.Add(a.View(), 0.0, "first.png");
    ExpectInputError([&] { acc.Add(small.View(), 0.001, "second.png"); }, "second.png: 31 x 24 px");
  }
  {
    imaging::FocusAccumulator acc(o);
    acc.Add(a.View(), 0.0);
    ExpectInputError([&] { acc.Add(b.View(), 0.0); }, "repeats");
  }
  {
    imaging::FocusAccumulator acc(o);
    acc.Add(a.View(), 0.0);
    acc.Add(b.View(), 0.001);
    ExpectInputError([&] { acc.Add(a.View(), 0.0005); }, "out of order");
  }
  {  // decreasing is an order too
    imaging::FocusAccumulator acc(o);
    for (int k = 0; k < 3; ++k) acc.Add(a.View(), -0.001 * k);
    EXPECT_EQ(acc.Finish().height.size_x, 32);
  }
  ExpectInputError([&] { (void)imaging::ReconstructFocusStack({a.View(), b.View()}, {0.0}, o); },
                            "2 images but 1 z positions");
  o.adaptive_window = false;  // a fixed window: its size is checked and must fit the image
  o.window = 4;
  ExpectInputError([&] { imaging::FocusAccumulator acc(o); }, "odd");
  o.window = 41;
  imaging::FocusAccumulator acc(o);
  ExpectInputError([&] { acc.Add(a.View(), 0.0); }, "smaller than the focus window");
}

}  // namespace
}  // namespace fvm
