#include "workflows/focus.h"

#include <fmt/core.h>

#include <cmath>
#include <string>

#include "core/input_error.h"
#include "core/statistics.h"
#include "imaging/tile_registration.h"  // SetImagingThreads

namespace fvm::workflows {
namespace {

// Over the finite values only: a pixel without a peak has no quality, and one NaN must not make the median NaN.
double MedianOrZero(const std::vector<float>& values) {
  std::vector<float> finite;
  finite.reserve(values.size());
  for (float v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  return finite.empty() ? 0.0 : HighMedian(finite);
}

// What the stack is called in messages: its list, or its first and last image.
std::string StackName(const std::vector<imaging::FocusStackEntry>& entries) {
  if (!entries.front().list.empty()) return entries.front().list.string();
  return entries.front().file.string() + " .. " + entries.back().file.string();
}

}  // namespace

imaging::FocusVariationOptions FocusOptions::Variation() const {
  imaging::FocusVariationOptions o;
  const auto parsed = imaging::ParseFocusMeasure(measure);
  if (!parsed) throw InputError("--measure: '" + measure + "' is not one of laplacian, tenengrad, variance");
  o.measure = *parsed;
  if (fit != "power" && fit != "gaussian" && fit != "parabolic") {
    throw InputError("--fit: '" + fit + "' is not one of power, gaussian, parabolic");
  }
  o.peak_fit = fit == "parabolic" ? imaging::PeakFit::kParabolic
               : fit == "gaussian" ? imaging::PeakFit::kGaussian
                                   : imaging::PeakFit::kPower;
  o.adaptive_window = window_px == 0;
  if (window_px != 0) o.window = window_px;
  o.min_quality = min_quality;
  o.keep_end_peaks = keep_end_peaks;
  o.dx_mm = pixel_mm;
  o.Check();
  return o;
}

void ComputeFocusFigures(FocusSummary& s) {
  const imaging::FocusResult& result = s.read.focus;
  s.map = result.height;
  if (s.slice_units) s.map.source += "; heights in slice units (no z step given)";
  s.stats = imaging::ComputeStats(s.map);
  std::vector<float> valid_quality, valid_u;
  for (std::size_t i = 0; i < s.map.z_mm.size(); ++i) {
    if (std::isfinite(s.map.z_mm[i])) valid_quality.push_back(result.quality[i]);
  }
  for (float u : result.u_z_mm) {
    if (std::isfinite(u)) valid_u.push_back(u);
  }
  s.median_quality = MedianOrZero(result.quality);
  s.median_valid_quality = MedianOrZero(valid_quality);
  s.median_u = MedianOrZero(valid_u);
}

FocusSummary ReconstructFocus(std::vector<imaging::FocusStackEntry> entries, const FocusOptions& options,
                              const std::function<void()>& on_image) {
  FocusSummary s;
  s.variation = options.Variation();
  s.aligned = options.align;
  s.entries = std::move(entries);
  s.slice_units = s.entries.front().line == 0 && !options.z_step_mm;
  imaging::SetImagingThreads(options.threads);
  imaging::FocusStackFilesOptions files;
  files.focus = s.variation;
  files.align = options.align;
  files.colour = options.colour;
  s.read = imaging::ReconstructFocusStackFiles(s.entries, files, on_image);
  ComputeFocusFigures(s);
  if (s.stats.valid_points == 0) {
    // A map of no height is no measurement: say so rather than write it and print medians of nothing.
    throw InputError(fmt::format(
        "{}: no pixel of the {} images has a focus peak of quality {:g} or more inside the stack, so there is no "
        "height to write; check that the images are one focus stack of a textured surface, in focus somewhere "
        "between the first and the last, lower --min-quality, or give --keep-end-peaks when the surface is in focus "
        "at an end",
        StackName(s.entries), s.entries.size(), options.min_quality));
  }
  return s;
}

}  // namespace fvm::workflows
