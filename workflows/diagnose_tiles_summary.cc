// What `fvm diagnose --layout/--scan` prints and its --json document, from the tile diagnosis itself.

#include <fmt/core.h>

#include <cmath>

#include "workflows/diagnose_tiles.h"
#include "workflows/distortion_options.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

Json Micrometres(double px, double pixel_mm) { return pixel_mm > 0.0 ? Json(px * pixel_mm * 1e3) : Json(nullptr); }

Json ResidualsJson(const OverlapResiduals& r, double pixel_mm) {
  return {{"points", r.points},
          {"rms_px", r.rms_px},
          {"mean_px", r.mean_px},
          {"rms_um", Micrometres(r.rms_px, pixel_mm)},
          {"mean_um", Micrometres(r.mean_px, pixel_mm)}};
}

std::string Component(const TileDiagnosis& d) { return fmt::format("order {}", d.field.field.order); }

std::string Explanation(const TileDiagnosis& d) {
  if (!d.significant) {
    return fmt::format("a rigid, undistorted image of every tile explains the overlaps: the field model's {} extra "
                       "coefficients do not earn their place against the correspondences' scatter (F = {:.3g}, p = "
                       "{:.2g}, dBIC = {:+.1f})",
                       d.extra_parameters, d.f_statistic, d.p_value, d.delta_bic);
  }
  return fmt::format("the overlaps disagree with a rigid image of every tile in a pattern one field of the objective "
                     "explains: the same displacement at the same pixel of every tile, up to {:.2f} px (F = {:.3g} on "
                     "{} extra coefficients, p = {:.2g}, dBIC = {:+.1f}); identify it with --distortion (fvm stitch, fvm calibrate --scan)",
                     d.largest_px, d.f_statistic, d.extra_parameters, d.p_value, d.delta_bic);
}

}  // namespace

Summary Summarize(const TileDiagnosis& d, const TileDiagnoseOptions& options) {
  const double mm = options.pixel_mm;
  Json doc;
  doc["source"] = d.source;
  doc["tiles"] = d.tiles;
  doc["size_px"] = {d.width_px, d.height_px};
  doc["pairs"] = d.pairs;
  doc["pairs_used"] = d.pairs_used;
  doc["effect"] = d.significant ? Json("field_distortion") : Json(nullptr);
  doc["component"] = d.significant ? Json(Component(d)) : Json("");
  doc["explanation"] = Explanation(d);
  doc["size"] = {{"value", d.largest_px}, {"unit", "px"}, {"value_um", Micrometres(d.largest_px, mm)}};
  doc["before"] = ResidualsJson(d.rigid, mm);
  doc["after"] = ResidualsJson(d.with_field, mm);
  const Json candidate = {{"effect", "field_distortion"}, {"component", Component(d)}, {"extra_parameters", d.extra_parameters},
                          {"f", d.f_statistic}, {"p_value", d.p_value}, {"delta_bic", d.delta_bic},
                          {"significant", d.significant}};
  doc["candidates"] = Json::array({candidate});
  doc["effects"] = Json::array();
  if (d.significant) {
    doc["effects"].push_back({{"effect", "field_distortion"},
                              {"component", Component(d)},
                              {"size", doc["size"]},
                              {"before", doc["before"]},
                              {"after", doc["after"]}});
  }
  doc["alpha"] = options.alpha;
  doc["noise"] = {{"point_sigma_px", d.point_sigma_px},
                  {"block_scatter_factor", d.field.block_scatter_factor},
                  {"pair_scatter_factor", d.field.pair_scatter_factor},
                  {"denominator_dof", d.field.block_dof}};
  doc["distortion"] = DistortionJson(d.field, true, mm);

  const auto um = [mm](double px) { return mm > 0.0 ? fmt::format(" ({:.3f} um)", px * mm * 1e3) : std::string(); };
  std::string text = fmt::format("fvm diagnose: {} {} tiles of {} x {} px, {} neighbour pairs ({} with correspondences the "
                                 "fit weighs)\n\n",
                                 d.source == "layout" ? "a layout of" : "calibration scans of", d.tiles, d.width_px,
                                 d.height_px, d.pairs, d.pairs_used);
  text += fmt::format("  {:<24} {:>6} {:>10} {:>10} {:>9}\n", "candidate", "extra", "F", "p", "dBIC");
  text += fmt::format("  {:<24} {:>6} {:>10.3g} {:>10.2g} {:>9.1f}{}\n", "field_distortion " + Component(d),
                      d.extra_parameters, d.f_statistic, d.p_value, d.delta_bic, d.significant ? "  significant" : "");
  text += fmt::format("  noise: {:.3f} px a point, widened {:.2f}x by the overlaps' quarter blocks ({:.2f}x by the loops)\n",
                      d.point_sigma_px, d.field.block_scatter_factor, d.field.pair_scatter_factor);
  if (d.significant) {
    text += fmt::format("\n  effect: field_distortion ({}), largest displacement {:.2f} px{}\n", Component(d), d.largest_px,
                        um(d.largest_px));
  } else {
    text += "\n  effect: none\n";
  }
  text += fmt::format("  {}\n\n", Explanation(d));
  text += fmt::format("  {:<34} {:>10} {:>10}\n", "overlap residual, px (rms / mean)", "before", "after");
  text += fmt::format("  {:<34} {:>10.4f} {:>10.4f}\n", "rms", d.rigid.rms_px, d.with_field.rms_px);
  text += fmt::format("  {:<34} {:>10.4f} {:>10.4f}\n", "mean", d.rigid.mean_px, d.with_field.mean_px);
  if (mm > 0.0) {
    text += fmt::format("  {:<34} {:>10.4f} {:>10.4f}\n", "rms, um", d.rigid.rms_px * mm * 1e3, d.with_field.rms_px * mm * 1e3);
  }
  text += fmt::format("  ({} correspondences, the same for both models)\n", d.with_field.points);
  if (d.significant) text += "\n" + DistortionText(d.field, true, mm);
  return {doc, text, std::nullopt};
}

}  // namespace fvm::workflows
