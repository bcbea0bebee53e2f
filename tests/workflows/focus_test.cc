#include "workflows/focus.h"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <cmath>

#include "artefacts/simulation/focus_stack_render.h"
#include "imaging/io/focus_stack_io.h"
#include "tests/support/test_support.h"

namespace fvm::workflows {
namespace {

// A tilted plane (1 um of rise across 96 px) photographed at 20 focal planes 1 um apart, written as 8-bit PNGs and
// given as files: without a z step the heights count slices from the first image, with one they are in mm, and
// both agree with the plane within 0.2 step rms (the goal for walls is 0.1 step; the small 96 px stack
// has fewer texture grains per window).
TEST(ReconstructFocus, ImagesGivenAsFilesGiveSliceUnitsOrMillimetres) {
  const fvm::testing::TempDir dir;
  const imaging::HeightMap plane = artefacts::TiltedPlane(96, 96, 0.001, 0.0105, 1e-3 / 0.096, 0.0);
  artefacts::FocusStackRenderOptions render;
  render.z_mm = artefacts::EvenZSteps(0.001, 0.001, 20);
  const artefacts::RenderedFocusStack stack = artefacts::RenderFocusStack(plane, render);
  std::vector<std::filesystem::path> files;
  for (size_t k = 0; k < stack.images.size(); ++k) {
    files.push_back(dir.path() / fmt::format("s{}.png", 100 + k));
    imaging::WriteStackImage(files.back(), stack.images[k]);
  }
  FocusOptions options;
  options.pixel_mm = 0.001;
  int images = 0;
  const FocusSummary slices = ReconstructFocus(imaging::ResolveFocusStack(files, std::nullopt), options, [&] { ++images; });
  EXPECT_EQ(images, 20);
  EXPECT_TRUE(slices.slice_units);
  options.z_step_mm = 0.001;
  const FocusSummary mm = ReconstructFocus(imaging::ResolveFocusStack(files, 0.001), options);
  EXPECT_FALSE(mm.slice_units);
  ASSERT_GT(mm.stats.valid_points, 96u * 96u / 2);
  double sum_slices = 0, sum_mm = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < plane.z_mm.size(); ++i) {
    if (!std::isfinite(mm.map.z_mm[i]) || !std::isfinite(slices.map.z_mm[i])) continue;
    const double truth_mm = plane.z_mm[i] - 0.001;  // heights from the first focal plane
    sum_mm += std::pow(mm.map.z_mm[i] - truth_mm, 2);
    sum_slices += std::pow(slices.map.z_mm[i] - truth_mm / 0.001, 2);
    ++n;
  }
  EXPECT_LT(std::sqrt(sum_mm / n), 0.2e-3);
  EXPECT_LT(std::sqrt(sum_slices / n), 0.2);
  EXPECT_GT(mm.median_u, 0.0);
  EXPECT_GT(mm.median_valid_quality, options.min_quality);
}

// The --json summary says how the stack's typical focus curve looks and how much of the two corrections it gates
// was applied. This stack's blur grows in quadrature from the texture's grain (a round top: shape ratio 4.88, 4 for
// a parabola) under a narrow curve (1 px of blur per um at 1 um steps: shoulder 0.76), so the slope beside bends
// applies in full and the steep walls' bias not at all.
TEST(ReconstructFocus, SummaryReportsTheFocusCurveAndTheSharesOfTheCorrectionsItGates) {
  const imaging::HeightMap plane = artefacts::TiltedPlane(96, 96, 0.001, 0.0105, 1e-3 / 0.096, 0.0);
  artefacts::FocusStackRenderOptions render;
  render.z_mm = artefacts::EvenZSteps(0.001, 0.001, 20);
  const artefacts::RenderedFocusStack stack = artefacts::RenderFocusStack(plane, render);
  FocusSummary s;
  for (std::size_t k = 0; k < stack.images.size(); ++k) s.entries.push_back({fmt::format("s{}.png", k), stack.z_mm[k]});
  s.variation.dx_mm = 0.001;
  s.read.focus = imaging::ReconstructFocusStack(stack.Views(), stack.z_mm, s.variation);
  ComputeFocusFigures(s);
  const imaging::FocusResult& focus = s.read.focus;
  const nlohmann::ordered_json json = Summarize(s, "h.x3p").json;
  EXPECT_EQ(json["focus_curve"]["shoulder"].get<double>(), focus.curve_shoulder);
  EXPECT_EQ(json["focus_curve"]["shape_ratio"].get<double>(), focus.curve_shape_ratio);
  EXPECT_EQ(json["slope_beside_bends_share"].get<double>(), focus.slope_beside_bends_share);
  EXPECT_EQ(json["steep_wall_bias_share"].get<double>(), focus.steep_wall_bias_share);
  EXPECT_GT(focus.curve_shape_ratio, 3.5);
  EXPECT_LT(focus.curve_shoulder, 1.3);
  EXPECT_EQ(focus.slope_beside_bends_share, 1.0);
  EXPECT_EQ(focus.steep_wall_bias_share, 0.0);
  EXPECT_NE(Summarize(s, "h.x3p").text.find("steep-wall bias 0.00"), std::string::npos);
  // Too few peaks to tell the curve's shape (its ratio 0): no curve, rather than a shape of 0.
  s.read.focus.curve_shoulder = 0.0, s.read.focus.curve_shape_ratio = 0.0;
  const Summary unknown = Summarize(s, "h.x3p");
  EXPECT_TRUE(unknown.json["focus_curve"].is_null());
  EXPECT_EQ(unknown.text.find("focus curve"), std::string::npos);
}

}  // namespace
}  // namespace fvm::workflows
