// Summarize(FocusSummary) of workflows/focus.h: the --json document and the text of `fvm focus`.

#include <fmt/core.h>

#include "workflows/focus.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

Json FocusJson(const FocusSummary& s) {
  const imaging::HeightMapStats& stats = s.stats;
  const bool valid = stats.valid_points > 0;
  Json out;
  out["images"] = s.entries.size();
  out["size_x"] = s.map.size_x;
  out["size_y"] = s.map.size_y;
  out["dx_mm"] = s.map.dx_mm;
  out["dy_mm"] = s.map.dy_mm;
  out["valid_points"] = stats.valid_points;
  out["z_min_mm"] = valid ? Json(stats.z_min_mm) : Json();
  out["z_max_mm"] = valid ? Json(stats.z_max_mm) : Json();
  out["z_unit"] = s.slice_units ? "slice" : "mm";
  out["u_z_median"] = valid ? Json(s.median_u) : Json();
  out["aligned"] = s.aligned;
  out["unregistered_images"] = s.read.unregistered;
  out["median_quality"] = s.median_quality;
  out["median_quality_valid"] = s.median_valid_quality;
  out["measure"] = imaging::FocusMeasureName(s.variation.measure);
  out["window"] = s.variation.adaptive_window ? Json("adaptive") : Json(s.variation.window);
  out["min_quality"] = s.variation.min_quality;
  const imaging::FocusResult& focus = s.read.focus;
  out["phase_bias_rms"] = focus.phase_bias_rms_mm > 0.0 ? Json(focus.phase_bias_rms_mm) : Json();
  out["phase_bias_declined"] = focus.phase_bias_declined.empty() ? Json() : Json(focus.phase_bias_declined);
  out["focus_curve"] = focus.curve_shape_ratio > 0.0  // 0: too few peaks to tell the curve's shape
                           ? Json{{"shoulder", focus.curve_shoulder}, {"shape_ratio", focus.curve_shape_ratio}}
                           : Json();
  out["slope_beside_bends_share"] = focus.slope_beside_bends_share;
  out["steep_wall_bias_share"] = focus.steep_wall_bias_share;
  return out;
}

std::string FocusText(const FocusSummary& s, const std::string& output) {
  const imaging::HeightMapStats& stats = s.stats;
  const imaging::FocusVariationOptions& v = s.variation;
  const char* unit = s.slice_units ? "slice" : "mm";
  const std::size_t points = s.map.z_mm.size();
  std::string t = fmt::format("{}\n", output);
  t += fmt::format("  stack          {} images, z {:.6f} .. {:.6f} {}{}\n", s.entries.size(), s.entries.front().z_mm,
                   s.entries.back().z_mm, unit, s.aligned ? ", aligned to the first" : "");
  t += fmt::format("  measure        {}, window {}, min quality {:g}\n", imaging::FocusMeasureName(v.measure),
                   v.adaptive_window ? std::string("adaptive 5/9 px") : fmt::format("{} px", v.window), v.min_quality);
  if (s.read.unregistered > 0) {
    t += fmt::format("  alignment      {} image(s) shared no sharp texture with their neighbour: kept its place\n",
                     s.read.unregistered);
  }
  t += fmt::format("  grid           {} x {} points, {:g} um pixels\n", s.map.size_x, s.map.size_y, s.map.dx_mm * 1e3);
  t += fmt::format("  valid points   {} of {} ({:.2f} %)\n", stats.valid_points, points,
                   points > 0 ? 100.0 * double(stats.valid_points) / double(points) : 0.0);
  if (stats.valid_points > 0) {
    if (s.slice_units) {
      t += fmt::format("  z range        {:.3f} .. {:.3f} slices\n", stats.z_min_mm, stats.z_max_mm);
      t += fmt::format("  u_z median     {:.3f} slices\n", s.median_u);
    } else {
      t += fmt::format("  z range        {:.6f} .. {:.6f} mm ({:.3f} um)\n", stats.z_min_mm, stats.z_max_mm,
                       (stats.z_max_mm - stats.z_min_mm) * 1e3);
      t += fmt::format("  u_z median     {:.4f} um\n", s.median_u * 1e3);
    }
  } else {
    t += "  no valid point: no pixel has a clear focus peak inside the stack\n";
  }
  t += fmt::format("  median quality {:.3g} (valid points {:.3g})\n", s.median_quality, s.median_valid_quality);
  const imaging::FocusResult& focus = s.read.focus;
  if (focus.phase_bias_rms_mm > 0.0) {
    t += s.slice_units ? fmt::format("  phase bias     {:.4f} slices rms taken off\n", focus.phase_bias_rms_mm)
                       : fmt::format("  phase bias     {:.4f} um rms taken off\n", focus.phase_bias_rms_mm * 1e3);
  } else if (!focus.phase_bias_declined.empty()) {
    t += fmt::format("  phase bias     none taken off: {}\n", focus.phase_bias_declined);
  }
  if (focus.curve_shape_ratio > 0.0) {
    t += fmt::format("  focus curve    shoulder {:.2f}, shape ratio {:.2f} (4 round top, 2 V); shares applied: "
                     "slope beside bends {:.2f}, steep-wall bias {:.2f}\n",
                     focus.curve_shoulder, focus.curve_shape_ratio, focus.slope_beside_bends_share,
                     focus.steep_wall_bias_share);
  }
  return t;
}

}  // namespace

Summary Summarize(const FocusSummary& summary, const std::string& output) {
  return {FocusJson(summary), FocusText(summary, output), std::nullopt};
}

}  // namespace fvm::workflows
