#include "imaging/focus_variation.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <variant>

#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/focus_height_maps.h"
#include "imaging/focus_peak.h"
#include "imaging/focus_phase_bias.h"
#include "imaging/focus_stack_curves.h"
#include "imaging/focus_slope_beside_bends.h"
#include "imaging/focus_window_centroid.h"
#include "imaging/focus_window_curvature.h"
#include "imaging/focus_steep_curvature_bias.h"

namespace fvm::imaging {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string Describe(std::string_view name, int index) {
  return name.empty() ? "image " + std::to_string(index + 1) + " of the stack" : std::string(name);
}

std::size_t PixelCount(const StackImageView& image) {
  return std::visit([](auto span) { return span.size(); }, image.pixels);
}

// Brightness in any scale a camera or a converter writes (0..1, 0..65535, photon counts) stays far below this; the
// focus measures square differences of neighbours in float, and beyond it they overflow to inf and NaN (an image
// all -3.4e38, a float format's "no data", left fvm focus with no valid point and a NaN median quality, issue 44).
constexpr float kMaxIntensity = 1e15f;
// The large window is taken where the surface's height changes by at most this many steps over its half-width
// (4 px): beyond, the second-order bias of the heights it mixes grows faster than its noise falls (on 40 deg walls
// the small window errs 0.2-0.3 step, the large one 0.3-0.55).
constexpr double kSpreadLimitSteps = 2.4;
// The uncertainty model (see Finish and FitPeak). A pixel's height comes from a window of 5 or 9 px, so its
// error is shared by its neighbours: on the independent stacks of ../shared/bench/focusgen.py the errors
// correlate 0.7-0.8 three pixels apart, and farther where the texture is coarse (2 px) or the blur grows linearly
// from a large diffraction floor (NA 0.9, 0.8 um: a focus curve with a sharp top, whose peak the fit pulls
// towards the nearest image by up to 0.15 step, which changes slowly over a tilted face). The heights' scatter
// about their 2 px local mean (the model's only such term before) sees 35-65 % of these errors depending on the
// optics and the texture, so u_z covered 75-88 % at a 2 px texture and at NA 0.9 with a 0.8 um floor. What they
// leave in the map is roughness at the window's scale: the Laplacian of the heights smoothed over 2 px, less its
// own local mean over 6 px (the surface's real curvature changes slowly and is no error), rms over 15 px, the
// surface's sharp bends (a calotte's rim) left out (focus_height_maps.cc); times 9 px^2 (about half a 9 px
// window's variance: the second-order term of a window's mean). The fit's own model error: on a face tilted by
// less than a step over a window the power fit errs by up to a tenth of a step depending on where the surface
// lies between two images (a bias that changes slowly across the map, which no roughness shows: 0.02-0.09 step
// rms on focusgen.py's flats, most at NA 0.9 with a 0.8 um floor and with a 2 px texture); the vertex's move when
// the fit keeps only the top three images (Peak::model) measures the curve's departure from the parabola there;
// on a slope the window's heights span steps and average that bias away, so the term falls as 1 / (1 + (slope
// times kModelSpanPx over the step)^2): from a step over about a window's side (8 px; with 4 px, walls of slope
// 0.2-0.45 step/px kept a third of the term, which their roughness already holds: walls covered 97-98.6 %,
// error / u_z 0.85-0.9 where the heights' roughness alone matched the errors). The terms overlap (the noise's
// errors show in the roughness and in the fits' disagreement too) and add in quadrature, each at a weight
// calibrated for 95 % coverage of 1.96 u_z on
// focusgen.py seeds 11 and 12 over 13 conditions (NA 0.3 to 0.9, floor 0.3 to 0.8 um, texture correlation 0.7 to
// 2 px; tests/bench/focus_conditions.py) and checked on seeds 13 and 14: the measure's noise per pixel over its
// floor propagated through the fit (scaled by the power fit's misfit, focus_peak.cc); the roughness; a share of
// the heights' scatter about their local mean; the model term; what the window's centroid correction leaves on
// a slope (a share of a pixel times the slope); a floor of a share of the step; and for a curve too narrow for
// the power fit (the 3-point log fit's error between images) a share of the step.
constexpr double kStepFraction = 0.005;
constexpr double kRoughnessPx2 = 9.0;
constexpr double kScatterScale = 0.09;
constexpr double kModelShare = 0.6;
constexpr double kModelSpanPx = 8.0;
constexpr double kSlopePx = 0.005;
// Where the peak fit's phase bias is taken off (focus_phase_bias.h), the level points' scatter about their local
// planes over 31 px is a direct measure of the errors left there, including those correlated over more than the
// roughness's reach (a 2 px texture) and the bias the fit leaves; it stands in for the map terms (the noise, the
// scatter, the roughness and the model term, which was the bias's proxy) in proportion to the bias taken off (the
// James-Stein share times the fade with the slope), at this weight (the terms that remain, the floor and the
// correction's own uncertainty, add to it), calibrated like the others on focusgen.py seeds 11 and 12: on their
// flats the roughness read 0.83-1.76 times the errors depending on the texture and the optics, the level scatter
// 0.75-0.93 times.
constexpr double kLevelScatterScale = 0.85;
// Where the phase bias is declined (too few level points, or too few phases among them: a flat about one period of the
// phase across, half its pixels invalid), nothing in the map measures it, yet the heights carry it: on focusgen.py's
// flats at NA 0.3 / 0.8 um / 2 px the errors keep a floor of 0.11-0.14 step where the map's terms say 0.09 (the quarter
// of the pixels with the smallest u_z covered 77-91 %, 85-94 % with this term; seeds 11-14). Its size predicted from
// the stack's own focus curve (PredictedPhaseBiasRms), faded with the slope as the correction fades, adds to the map's
// terms, at weight 1 (a standard uncertainty of its own, the prediction agreeing with the measured bias where the
// correction applies). It adds to the model term rather than replacing it: the model term follows each pixel's own
// curve and is smallest (0.035-0.04 step) where those errors exceed u_z; taking the larger of the two instead left
// those flats at 90.2-92.5 %. Where the correction applies, even in part, the level scatter and the correction's own
// uncertainty hold what it leaves, and the prediction is not added (added there by the share not taken off, it pushed
// NA 0.9 / 0.3 um / 0.7 px flats above 97 %).

}  // namespace

std::string FocusMeasureName(FocusMeasure measure) {
  switch (measure) {
    case FocusMeasure::kModifiedLaplacian:
      return "laplacian";
    case FocusMeasure::kTenengrad:
      return "tenengrad";
    case FocusMeasure::kVariance:
      return "variance";
  }
  return "?";
}

std::optional<FocusMeasure> ParseFocusMeasure(std::string_view name) {
  for (FocusMeasure m : {FocusMeasure::kModifiedLaplacian, FocusMeasure::kTenengrad, FocusMeasure::kVariance}) {
    if (name == FocusMeasureName(m)) return m;
  }
  return std::nullopt;
}

void FocusVariationOptions::Check() const {
  if (window < 3 || window > 51 || window % 2 == 0) {
    throw InputError("focus variation: the window must be an odd number of pixels from 3 to 51, not " +
                     std::to_string(window));
  }
  if (!(dx_mm > 0.0) || !std::isfinite(dx_mm) || !(dy_mm >= 0.0) || !std::isfinite(dy_mm)) {
    throw InputError("focus variation: the pixel size must be positive and finite (mm)");
  }
  if (!(min_quality >= 0.0) || !std::isfinite(min_quality)) {
    throw InputError("focus variation: the minimum quality must be 0 or more (peak over mean focus measure)");
  }
}

struct FocusAccumulator::State {
  FocusVariationOptions options;
  int width = 0, height = 0;
  std::vector<double> z;
  FocusCurves curves;
  // Images taken but not yet folded into the curves (a batch, see focus_stack_curves.h), copied into buffers
  // that serve batch after batch; the colour images only when they are not the grey ones. With `borrow` (a
  // stack held in memory by ReconstructFocusStack, alive until Finish) the caller's images are not copied.
  std::vector<StackImage> pending = std::vector<StackImage>(kFocusBatch), pending_colour = pending;
  std::vector<StackImageView> views = std::vector<StackImageView>(kFocusBatch), colour_views = views;
  int pending_count = 0;
  bool colour = false;
  bool borrow = false;

  void Pend(const StackImageView& image, const StackImageView* texture) {
    const std::size_t j = std::size_t(pending_count);
    if (borrow) {
      views[j] = image;
      if (texture) colour_views[j] = *texture;
    } else {
      CopyInto(image, pending[j]);
      views[j] = pending[j].View();
      if (texture) CopyInto(*texture, pending_colour[j]), colour_views[j] = pending_colour[j].View();
    }
    if (++pending_count == kFocusBatch) Flush();
  }

  void Flush() {
    curves.Take(views.data(), colour ? colour_views.data() : nullptr, pending_count);
    pending_count = 0;
  }
};

FocusAccumulator::FocusAccumulator(const FocusVariationOptions& options) : state_(std::make_unique<State>()) {
  options.Check();
  state_->options = options;
}

FocusAccumulator::~FocusAccumulator() = default;

int FocusAccumulator::count() const { return static_cast<int>(state_->z.size()); }

void FocusAccumulator::Add(const StackImageView& image, double z_mm, std::string_view name,
                           const StackImageView* colour) {
  State& s = *state_;
  const int k = count();
  const std::string what = Describe(name, k);
  if (image.width <= 0 || image.height <= 0 || image.channels != 1 ||
      PixelCount(image) != std::size_t(image.width) * std::size_t(image.height)) {
    throw InputError(what + ": empty image, not one grey channel, or a pixel count that does not match its size");
  }
  const StackImageView& texture = colour ? *colour : image;
  if (texture.width != image.width || texture.height != image.height ||
      (texture.channels != 1 && texture.channels != 3) ||
      PixelCount(texture) != std::size_t(image.width) * std::size_t(image.height) * std::size_t(texture.channels)) {
    throw InputError(what + ": the colour image differs in size from the grey one or has not 1 or 3 channels");
  }
  if (k > 0 && texture.channels != s.curves.texture_channels) {
    throw InputError(what + ": " + std::to_string(texture.channels) + " colour channel(s), unlike the first image's " +
                     std::to_string(s.curves.texture_channels));
  }
  if (!std::isfinite(z_mm)) throw InputError(what + ": the z position is not a finite number");
  if (const auto* floats = std::get_if<std::span<const float>>(&image.pixels)) {
    const auto absurd = std::find_if(floats->begin(), floats->end(), [](float v) { return std::abs(v) > kMaxIntensity; });
    if (absurd != floats->end()) {
      const std::size_t i = static_cast<std::size_t>(absurd - floats->begin());
      throw InputError(what + ": pixel (" + std::to_string(i % std::size_t(image.width)) + ", " +
                       std::to_string(i / std::size_t(image.width)) + ") has the brightness " + FormatShortest(*absurd) +
                       ", beyond 1e15 in size, which no camera records (a 'no data' marker?); give the image as the "
                       "camera took it");
    }
  }
  if (k == 0) {
    const int window = s.options.adaptive_window ? kAdaptiveWindows[std::size(kAdaptiveWindows) - 1] : s.options.window;
    if (image.width < window || image.height < window) {
      throw InputError(what + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " px is smaller than the focus window (" + std::to_string(window) + " px)");
    }
    s.width = image.width;
    s.height = image.height;
    const std::size_t n = std::size_t(s.width) * std::size_t(s.height);
    FocusCurves& curves = s.curves;
    curves = FocusCurves{};
    curves.width = s.width;
    curves.height = s.height;
    curves.measure = s.options.measure;
    curves.parallel = s.options.parallel;
    if (s.options.adaptive_window) {
      for (int w : kAdaptiveWindows) {
        curves.windows.emplace_back().Reset(w, true, n);
      }
    } else {
      curves.windows.emplace_back().Reset(s.options.window, false, n);
    }
    curves.texture_channels = texture.channels;
    curves.texture.resize(n * std::size_t(texture.channels));  // set by the first batch, in parallel
  } else {
    if (image.width != s.width || image.height != s.height) {
      throw InputError(what + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " px, but the stack's first image is " + std::to_string(s.width) + " x " +
                       std::to_string(s.height) + " px; every image of a stack must have the same size");
    }
    const double step = z_mm - s.z.back();
    const double direction = k >= 2 ? s.z[1] - s.z[0] : step;
    if (step == 0.0) {
      throw InputError(what + ": z = " + std::to_string(z_mm) + " mm repeats the previous image's position; "
                       "each image of a stack needs its own z");
    }
    if ((step > 0.0) != (direction > 0.0)) {
      throw InputError(what + ": z = " + std::to_string(z_mm) + " mm is out of order (previous " +
                       std::to_string(s.z.back()) + " mm); list the images by increasing or decreasing z");
    }
  }
  s.z.push_back(z_mm);

  if (k == 0) s.colour = colour != nullptr;
  s.Pend(image, s.colour ? &texture : nullptr);
}

FocusResult FocusAccumulator::Finish() const {
  const State& s = *state_;
  const int n = count();
  if (n < 3) {
    throw InputError("focus variation: the stack has " + std::to_string(n) +
                     " image(s); at least 3 are needed (a focus peak needs an image on either side of it)");
  }
  State& folding = *state_;  // the images still pending are folded in, which changes no result
  folding.Flush();
  FocusResult result;
  HeightMap& map = result.height;
  map.size_x = s.width;
  map.size_y = s.height;
  map.dx_mm = s.options.dx_mm;
  map.dy_mm = s.options.dy_mm > 0.0 ? s.options.dy_mm : s.options.dx_mm;
  const std::string windows =
      s.options.adaptive_window ? "adaptive window 5/9 px" : "window " + std::to_string(s.options.window) + " px";
  map.source = "focus variation (" + FocusMeasureName(s.options.measure) + ", " + windows + ", " +
               std::to_string(n) + " images)";
  const std::size_t size = std::size_t(s.width) * std::size_t(s.height);
  const std::vector<WindowCurves>& curves = s.curves.windows;
  const WindowCurves& large = curves.back();
  const HugeVector<std::int32_t>& peak_index = large.index;
  // The result's maps, each filled (and its fresh pages faulted in, which on a virtual machine costs more than
  // the filling) by its own thread: one after the other they were the reconstruction's longest serial part.
  const std::function<void()> allocations[] = {
      [&] { ReserveInHugePages(map.z_mm, size), map.z_mm.resize(size); },
      [&] { ReserveInHugePages(result.u_z_mm, size), result.u_z_mm.resize(size); },
      [&] { ReserveInHugePages(result.quality, size), result.quality.resize(size); },
      [&] { ReserveInHugePages(result.window_px, size), result.window_px.assign(size, kNaN); },
      [&] {
        ReserveInHugePages(result.peak_index, size);
        result.peak_index.assign(peak_index.begin(), peak_index.end());
      },
      [&] {
        ReserveInHugePages(result.texture, s.curves.texture.size());
        result.texture.assign(s.curves.texture.begin(), s.curves.texture.end());
      }};
  const auto allocate = [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) allocations[i]();
  };
  const cv::Range all_maps(0, int(std::size(allocations)));
  if (s.options.parallel) {
    cv::parallel_for_(all_maps, allocate, double(all_maps.end));
  } else {
    allocate(all_maps);
  }
  result.texture_channels = s.curves.texture_channels;
  const double step = std::abs(s.z.back() - s.z.front()) / double(n - 1);
  const double origin = s.z.front();

  std::vector<float> model(size);  // each height's Peak::model
  const bool coarse = CoarselySampled(large, s.z.size(), s.options.min_quality);
  // The largest window's heights everywhere; their slope says where the smaller windows serve instead (walls),
  // and only there are their peaks fitted.
  ForStripes(s.height, s.options.parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(s.width); i < std::size_t(r1) * std::size_t(s.width); ++i) {
      const Peak p = FitPeak(large, i, s.z, s.options, coarse);
      map.z_mm[i] = p.z;
      model[i] = static_cast<float>(p.model);
      result.u_z_mm[i] = static_cast<float>(p.u);
      result.quality[i] = p.quality;
    }
  });
  MapPool pool(s.width, s.height, s.options.parallel);  // before the maps it hands out, which it outlives
  Slope slope = SmoothHeights(map.z_mm, origin, pool).slope;
  const double spread_limit = kSpreadLimitSteps * step;

  ForStripes(s.height, s.options.parallel, [&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      for (int col = 0; col < s.width; ++col) {
        const std::size_t i = std::size_t(r) * std::size_t(s.width) + std::size_t(col);
        // The largest window's quality decides validity: its peak over mean is the least noisy, and a small
        // window's noise peak on a texture-free spot must not pass for a height.
        if (!(result.quality[i] >= s.options.min_quality)) continue;
        double z = map.z_mm[i], u_noise = result.u_z_mm[i], window = large.window;
        const float g = slope.Magnitude(r, col);  // mm per px
        const auto fits = [&](const WindowCurves& c) { return g * (c.window / 2) <= spread_limit; };
        // The large window where the heights over its half-width fit the limit, else the small one.
        if (curves.size() > 1 && !(fits(large) && std::isfinite(z))) {
          const WindowCurves& smaller = curves[curves.size() - 2];
          const Peak small = FitPeak(smaller, i, s.z, s.options, coarse);
          if (std::isfinite(small.z)) {
            z = small.z, u_noise = small.u, window = smaller.window;
            model[i] = static_cast<float>(small.model);
          }
        }
        map.z_mm[i] = z;
        result.u_z_mm[i] = std::isfinite(z) ? static_cast<float>(u_noise) : kNaN;
        if (std::isfinite(z)) result.window_px[i] = static_cast<float>(window);
      }
    }
  });
  slope = {};  // its maps go back to the pool
  // Each window's height is that under the centroid of its pixels' sharpness: moved to its centre along the
  // slope of the map as now chosen (focus_window_centroid.h); beside a sharp bend, where the stack's focus curves are
  // narrow, along the slope of the pixel's own side of it (focus_slope_beside_bends.h).
  SmoothedHeights chosen = SmoothHeights(map.z_mm, origin, pool);
  const Slope& final_slope = chosen.slope;
  {
    cv::Mat beside_x = pool.Map(), beside_y = pool.Map();
    const float *gx = final_slope.x.ptr<float>(), *gy = final_slope.y.ptr<float>();
    const double share = NarrowCurveShare(MeasureCurveShape(large, s.z.size(), s.options.min_quality, gx, gy, step));
    result.slope_beside_bends_share = share;
    SlopeBesideBends(pool, chosen.smooth.ptr<float>(), gx, gy, chosen.valid.ptr<float>(), step, share,
                     beside_x.ptr<float>(), beside_y.ptr<float>());
    CentroidCorrectionInput in;
    in.width = s.width, in.height = s.height, in.parallel = s.options.parallel;
    in.texture = &result.texture, in.channels = result.texture_channels;
    in.windows = &curves, in.window_px = &result.window_px;
    in.slope_x = beside_x.ptr<float>(), in.slope_y = beside_y.ptr<float>();
    CorrectWindowCentroids(in, map.z_mm);
  }
  // The peak fit's phase-locked bias, measured on this map's level points and taken off (focus_phase_bias.h).
  std::vector<float> u_phase;
  PhaseBias phase_bias;
  {
    PhaseBiasInput in;
    in.width = s.width, in.height = s.height, in.z_mm = &map.z_mm;
    in.slope_x = final_slope.x.ptr<float>(), in.slope_y = final_slope.y.ptr<float>();
    in.origin_mm = origin, in.step_mm = step, in.parallel = s.options.parallel;
    // The heights the phase is read from: their local mean over the points the correction applies to (weights
    // fading with the slope as it does), from the heights `chosen` was smoothed from.
    cv::Mat weight = pool.Map();
    const double fade_scale = 1.0 / (kPhaseSmoothingSlope * step);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* w = weight.ptr<float>(r);
        const float* v = chosen.valid.ptr<float>(r);
        for (int col = 0; col < s.width; ++col) {
          const double g = final_slope.Magnitude(r, col) * fade_scale;
          w[col] = v[col] * float(std::exp(-g * g));
        }
      }
    });
    const cv::Mat phase_heights = WeightedLocalMean(chosen.heights, weight, kPhaseSmoothingPx, pool);
    in.phase_heights = phase_heights.ptr<float>();
    for (int k = 0; k < n; ++k) {
      const double even = origin + (s.z.back() > origin ? k : -k) * step;
      in.uneven_steps = std::max(in.uneven_steps, std::abs(s.z[std::size_t(k)] - even) / step);
    }
    phase_bias = EstimatePhaseBias(in);
    CorrectPhaseBias(phase_bias, in, map.z_mm, u_phase);
    result.phase_bias_rms_mm = phase_bias.Rms();
    result.phase_bias_declined = phase_bias.reason;
  }
  chosen = {};  // its maps go back to the pool

  // The errors no single focus curve shows: the heights' scatter from pixel to pixel, their roughness at the
  // window's scale (errors shared by a window's pixels, see kRoughnessScale), and on a slope what the centroid
  // correction leaves. Both from the corrected heights.
  SmoothedHeights corrected = SmoothHeights(map.z_mm, origin, pool);
  const cv::Mat scatter = LocalScatter(corrected, pool);
  const Slope corrected_slope = corrected.slope;
  const WindowScaleMaps window_scale = WindowScaleRoughness(std::move(corrected), pool);
  const cv::Mat& roughness = window_scale.roughness;
  // Each window's height is that under its centre on a curved surface too (focus_window_curvature.h), from the
  // surface's curvature the roughness leaves (a move this smooth does not change the roughness); and on steep curved
  // walls, where the stack's focus curves are narrow with a sharp top, the bias that mixing the window's heights
  // leaves there (focus_steep_curvature_bias.h).
  const float* curvature = window_scale.curvature.ptr<float>();
  CorrectWindowCurvature(s.width, s.height, s.options.parallel, curves, result.window_px, curvature, map.z_mm);
  std::vector<float> unremoved;  // the steep walls' bias near a bend, which u_z holds instead
  double u_predicted_phase = 0.0;  // the phase bias predicted where it was not measured (see kLevelScatterScale)
  {
    const float *gx = corrected_slope.x.ptr<float>(), *gy = corrected_slope.y.ptr<float>();
    const FocusCurveShape shape = MeasureCurveShape(large, s.z.size(), s.options.min_quality, gx, gy, step);
    if (!phase_bias.applied && s.options.peak_fit == PeakFit::kPower) {
      const double power = -2.0 / BlurExponent(s.options.measure);  // the power fit's transform (FitPeak)
      u_predicted_phase = PredictedPhaseBiasRms(shape.rise1, shape.rise2, power) * step;
    }
    const double share = SteepCurvatureBiasShare(shape);
    result.curve_shoulder = shape.shoulder, result.curve_shape_ratio = shape.cusp;
    result.steep_wall_bias_share = share;
    CorrectSteepCurvatureBias(s.width, s.height, s.options.parallel, share, step, curves, result.window_px, gx, gy,
                              curvature, window_scale.filled_curvature.ptr<float>(), map.z_mm, unremoved);
  }
  const double u_step = kStepFraction * step;
  ForStripes(s.height, s.options.parallel, [&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      const float* roughness_row = roughness.ptr<float>(r);
      const float* scatter_row = scatter.ptr<float>(r);
      for (int col = 0; col < s.width; ++col) {
        const std::size_t i = std::size_t(r) * std::size_t(s.width) + std::size_t(col);
        if (!std::isfinite(map.z_mm[i])) continue;
        const double u_noise = result.u_z_mm[i], u_scatter = kScatterScale * scatter_row[col];
        const double u_roughness = kRoughnessPx2 * roughness_row[col];
        const double g = corrected_slope.Magnitude(r, col), u_slope = kSlopePx * g;
        const double span_steps = g * kModelSpanPx / step;
        const double u_model = kModelShare * model[i] / (1.0 + span_steps * span_steps);
        const double u_predicted = u_predicted_phase * PhaseBiasFade(g, step);
        double u_map = u_noise * u_noise + u_scatter * u_scatter + u_roughness * u_roughness + u_model * u_model +
                       u_predicted * u_predicted;
        // Where the phase bias was taken off, the level points' own scatter about their local planes (what the
        // correction leaves) stands in for these terms, by the share of the bias taken off.
        const double level = phase_bias.LevelScatter(r, col);
        if (std::isfinite(level)) {
          const double share = phase_bias.shrinkage * phase_bias.Fade(g), u_level = kLevelScatterScale * level;
          u_map = (1.0 - share) * u_map + share * u_level * u_level;
        }
        result.u_z_mm[i] = static_cast<float>(
            std::sqrt(u_map + u_step * u_step + u_slope * u_slope + double(u_phase[i]) * double(u_phase[i]) +
                      double(unremoved[i]) * double(unremoved[i])));
      }
    }
  });
  return result;
}

FocusResult ReconstructFocusStack(const std::vector<StackImageView>& images, const std::vector<double>& z_mm,
                                  const FocusVariationOptions& options) {
  if (images.size() != z_mm.size()) {
    throw InputError("focus variation: " + std::to_string(images.size()) + " images but " +
                     std::to_string(z_mm.size()) + " z positions");
  }
  FocusAccumulator accumulator(options);
  accumulator.state_->borrow = true;  // the images outlive the accumulator
  for (std::size_t i = 0; i < images.size(); ++i) accumulator.Add(images[i], z_mm[i]);
  return accumulator.Finish();
}

}  // namespace fvm::imaging
