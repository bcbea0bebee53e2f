// Focus variation on stacks this project did not render: ../shared/bench/focusgen.py, written from optics apart
// from the project, renders each object point spread by its own defocus (scatter) with a diffraction floor sigma0
// in focus and a band-limited texture, and writes the true heights beside the images. The scene is the bench's:
// a tilted textured face with a 35 um calotte whose walls reach 24 deg, 1 um pixels and steps. Heights are judged
// per region as ../shared/bench/check judges them (the flat beyond the rim, the wall from half the footprint
// radius to the rim, the bottom inside it) against the step, and u_z by the share of errors within 1.96 u_z.
// Skips where ../shared or Debian's python3-numpy, python3-scipy, python3-tifffile are absent.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "imaging/io/focus_stack_files.h"
#include "imaging/io/height_map_image.h"
#include "tests/support/test_support.h"

namespace fvm {
namespace {

const std::filesystem::path kBench = FVM_BENCH_DIR;
constexpr const char* kPython = "/usr/bin/python3";

bool BenchUsable() {
  if (!std::filesystem::exists(kBench / "focusgen.py") || !std::filesystem::exists(kPython)) return false;
  const std::string probe = std::string(kPython) + " -c 'import numpy, scipy, tifffile' >/dev/null 2>&1";
  return std::system(probe.c_str()) == 0;
}

struct RegionFigures {
  double rms_steps[3] = {0, 0, 0};  // flat, wall, bottom
  double coverage[3] = {0, 0, 0};
  double standardised_rms[3] = {0, 0, 0};  // rms of error / u_z
  std::size_t count[3] = {0, 0, 0};
  double valid_share = 0.0;
  // Within 3-12 px inside the rim (part of the wall): rms u_z over rms error. The rim's bend is no roughness, so
  // u_z there should follow the errors as on the rest of the wall.
  double rim_ratio = 0.0;
  double steep_wall_bias_share = 0.0;  // the share of the steep-wall correction the stack's curves gave
};

// Renders the stack with focusgen.py's `arguments` in `dir`, reconstructs it as `fvm focus` does, and compares.
RegionFigures RenderAndMeasure(const std::filesystem::path& dir, const std::string& arguments) {
  const std::string command = std::string(kPython) + " " + (kBench / "focusgen.py").string() + " " +
                              dir.string() + " " + arguments + " >/dev/null";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  nlohmann::json truth;
  std::ifstream(dir / "truth.json") >> truth;
  imaging::HeightMapImageOptions read;
  read.dx_mm = truth["pixel_mm"].get<double>();
  const imaging::HeightMap surface = imaging::ReadHeightMapImage(dir / "truth.tif", read);
  imaging::FocusStackFilesOptions o;
  o.focus.dx_mm = read.dx_mm;
  const imaging::FocusResult r =
      imaging::ReconstructFocusStackFiles(imaging::ResolveFocusStack({dir / "stack.csv"}, std::nullopt), o).focus;
  EXPECT_EQ(r.height.size_x, surface.size_x);
  EXPECT_EQ(r.height.size_y, surface.size_y);

  const double step_mm = truth["step_mm"].get<double>();
  const double cx = truth["surface_info"]["centre_px"][0].get<double>();
  const double cy = truth["surface_info"]["centre_px"][1].get<double>();
  const double a = truth["surface_info"]["footprint_radius_px"].get<double>();
  RegionFigures f;
  double sum[3] = {0, 0, 0}, standardised[3] = {0, 0, 0};
  std::size_t covered[3] = {0, 0, 0}, compared = 0, valid = 0, rim_count = 0;
  double rim_u2 = 0.0, rim_e2 = 0.0;
  constexpr int kBorder = 5;
  for (int y = kBorder; y < surface.size_y - kBorder; ++y) {
    for (int x = kBorder; x < surface.size_x - kBorder; ++x) {
      ++compared;
      const std::size_t i = std::size_t(y) * std::size_t(surface.size_x) + std::size_t(x);
      const double z = r.height.z_mm[i];
      if (!std::isfinite(z)) continue;
      ++valid;
      const double radius = std::hypot(x - cx, y - cy);
      const int region = radius > a + 3 ? 0 : radius > a / 2 && radius < a - 3 ? 1 : radius < a / 2 ? 2 : -1;
      if (region < 0) continue;  // the rim's 3 px either side, as the bench leaves them out
      const double d = z - surface.z_mm[i];
      if (radius > a - 12 && radius < a - 3) {
        rim_u2 += double(r.u_z_mm[i]) * double(r.u_z_mm[i]), rim_e2 += d * d, ++rim_count;
      }
      sum[region] += d * d;
      standardised[region] += d * d / (double(r.u_z_mm[i]) * double(r.u_z_mm[i]));
      covered[region] += std::abs(d) <= 1.96 * r.u_z_mm[i];
      ++f.count[region];
    }
  }
  for (int k = 0; k < 3; ++k) {
    f.rms_steps[k] = std::sqrt(sum[k] / double(f.count[k])) / step_mm;
    f.coverage[k] = double(covered[k]) / double(f.count[k]);
    f.standardised_rms[k] = std::sqrt(standardised[k] / double(f.count[k]));
  }
  f.valid_share = double(valid) / double(compared);
  f.rim_ratio = rim_count > 0 ? std::sqrt(rim_u2 / rim_e2) : 0.0;
  f.steep_wall_bias_share = r.steep_wall_bias_share;
  std::printf(
      "focusgen.py %s: rms flat %.3f, wall %.3f, bottom %.3f step; coverage %.3f, %.3f, %.3f; error / u_z rms %.2f, "
      "%.2f, %.2f; valid %.4f; rim u_z / error %.2f; focus curve shoulder %.2f, shape %.2f, steep-wall share %.2f\n",
      arguments.c_str(), f.rms_steps[0], f.rms_steps[1], f.rms_steps[2], f.coverage[0], f.coverage[1], f.coverage[2],
      f.standardised_rms[0], f.standardised_rms[1], f.standardised_rms[2], f.valid_share, f.rim_ratio,
      r.curve_shoulder, r.curve_shape_ratio, r.steep_wall_bias_share);
  return f;
}

struct Condition {
  const char* name;
  std::string arguments;
  double max_rms_steps;  // per region
  double min_valid_share = 0.99;
  double max_coverage = 0.99;  // per region
  double max_rim_ratio = 10.0;
  double min_coverage = 0.90;  // per region
  double steep_wall_bias_share = -1.0;  // the share expected of the steep-wall correction; below 0: not checked
};

class FocusIndependentStacks : public ::testing::TestWithParam<Condition> {};

// Tolerances. The bench's own scene (NA 0.4, sigma0 0.6 um, texture correlation 1 px; measured 0.053-0.057 flat,
// 0.081-0.082 wall, 0.054-0.057 bottom on seeds 1-3) and a coarser texture under a wider aperture (NA 0.6, sigma0
// 0.45 um, 1.5 px; 0.056 / 0.082 / 0.055 on seed 6; 0.070 / 0.079 / 0.058 on seed 8) are held at the goal,
// 0.1 step rms in every region. Two conditions where the physics limits the accuracy are held at what is measured
// plus ~15 %, and their u_z must say so: NA 0.9 with an 0.8 um floor, where the blur grows linearly from the floor
// and the focus curve's sharp top pulls peaks towards the nearest image (0.11-0.12 step on the flat, 0.11 on the
// wall, seeds 11 and 12), and the same optics with a 2 px texture (0.12-0.15 step, 5-7 % of the pixels below
// --min-quality 2). u_z: the 95 % coverage of 1.96 u_z measured at 92.2-97.7 % per region on the first two and at
// 90.6-97.2 % on the last two (the walls the lowest: the sharp top's bias, which the model term holds only where a
// window spans less than a step; 78-84 % with the model that counted only the heights' pixel-to-pixel scatter,
// 93-99 % before the model term); a region here holds a few hundred independent patches (errors correlate over
// the 9 px window), so one seed's coverage scatters by about 1.5 %: held at 90-99 %. The rms of error / u_z,
// measured 0.86-1.18 on them, is held at 0.7-1.3.
// A long depth of field over a coarse texture (NA 0.3, sigma0 0.3 um, 2 px; seed 16, apart from the seeds 11 and 12
// the uncertainty model is calibrated on): 0.24 step on the flat, 0.21 on the wall, 0.20 on the bottom, 57 % of
// the pixels valid, held at measured plus ~15 %. Its flat's coverage was 88.8 % when u_z missed the power fit's
// model error (the bias of where the surface lies between two images, which no roughness shows); 92.6 % now. Its
// wall's u_z was on the safe side (98.9 %, error / u_z rms 0.77) while the holes on its slope (43 % of the pixels)
// inflated the roughness; with the smooth heights a local plane fit (focus_height_maps.cc) and the model term
// gone once a window spans a step, 96.1 % and 0.96: held at 98 %. The walls at NA 0.9 with a 0.8 um floor covered
// 89.9 % (seed 9) and 91.6 % (seed 10), error / u_z 1.21 and 1.15, held at 88 %, while on slopes beyond 0.3 um/px
// their heights were 0.05-0.09 step too high; with that bias taken off (focus_steep_curvature_bias.h) 94.4 % and
// 93.3 %, error / u_z 1.05 and 1.10: held at 90 % like the rest.
// The same long depth of field under a 0.8 um floor (seed 12, NA 0.3, 2 px): the phase bias is declined (a flat
// about one period of the phase across, half its pixels invalid), and the flat keeps a phase-locked error of
// 0.05-0.08 step that no map term shows: its flat covered 89.5 % (error / u_z 1.18) until u_z took the bias's
// size predicted from the stack's own focus curve (focus_phase_bias.h, PredictedPhaseBiasRms): 92.1 %, held at
// 91 %; 0.177 / 0.205 / 0.146 step, held at measured plus ~15 %.
// Beside the rim (3-12 px inside it) u_z read the rim's bend as roughness: 1.65-1.8 times the errors' rms there
// on the first two conditions' optics (focusgen.py seeds 11 and 12), against 1.1-1.25 on the rest of the wall;
// with the bends left out of the roughness (focus_height_maps.cc) 1.29-1.30 on seeds 7 and 8: held at 1.45. At
// NA 0.9 with a 0.8 um floor the window's error beside the rim is larger than the bend term allows (0.64-0.65).
// The steep-wall correction (focus_steep_curvature_bias.h) is gated by the shape of the stack's focus curves: full
// under focusgen.py's default blur at NA 0.9 with a 0.8 um floor (sigma0 + k |dz|, the floor added to the width: a
// V-topped curve, shape ratio 2.57-2.82 on seeds 9, 11 and 12), none at NA 0.4 (V-topped too, 2.81, but wide:
// the best image's neighbours hold 1.62 of its peak, seed 7). The project's renderer,
// whose blur grows in quadrature from its floor, gets none (focus_accuracy_test.cc); so does focusgen.py with
// --blur quadrature (shape ratio 4.1-4.5).

TEST_P(FocusIndependentStacks, PerRegionAccuracyAndCoverage) {
  if (!BenchUsable()) GTEST_SKIP() << kBench << " or python3 with numpy, scipy and tifffile is absent";
  const Condition& c = GetParam();
  const testing::TempDir dir;
  const RegionFigures f = RenderAndMeasure(dir.path() / "stack", c.arguments);
  EXPECT_GT(f.valid_share, c.min_valid_share);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(f.count[k], 3000u) << "region " << k;
    EXPECT_LT(f.rms_steps[k], c.max_rms_steps) << "region " << k;
    EXPECT_GE(f.coverage[k], c.min_coverage) << "region " << k;
    EXPECT_LE(f.coverage[k], c.max_coverage) << "region " << k;
    EXPECT_GE(f.standardised_rms[k], 0.7) << "region " << k;
    EXPECT_LE(f.standardised_rms[k], 1.3) << "region " << k;
  }
  EXPECT_GT(f.rim_ratio, 0.0);
  EXPECT_LE(f.rim_ratio, c.max_rim_ratio);
  if (c.steep_wall_bias_share >= 0.0) {
    EXPECT_EQ(f.steep_wall_bias_share, c.steep_wall_bias_share);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Focusgen, FocusIndependentStacks,
    ::testing::Values(Condition{"bench_scene", "--seed 7", 0.1, 0.99, 0.99, 1.45, 0.90, 0.0},
                      Condition{"coarser_texture_NA06", "--seed 8 --na 0.6 --sigma0-um 0.45 --texture-px 1.5", 0.1,
                                0.99, 0.99, 1.45},
                      Condition{"sharp_top_NA09_floor08", "--seed 9 --na 0.9 --sigma0-um 0.8 --texture-px 0.7", 0.14,
                                0.99, 0.99, 10.0, 0.90, 1.0},
                      Condition{"coarse_texture_NA09_floor08", "--seed 10 --na 0.9 --sigma0-um 0.8 --texture-px 2",
                                0.17, 0.9, 0.99, 10.0},
                      Condition{"coarse_texture_NA03_floor03", "--seed 16 --na 0.3 --sigma0-um 0.3 --texture-px 2",
                                0.27, 0.5, 0.98},
                      Condition{"declined_phase_bias_NA03_floor08", "--seed 12 --na 0.3 --sigma0-um 0.8 --texture-px 2",
                                0.24, 0.45, 0.98, 10.0, 0.91}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace fvm
