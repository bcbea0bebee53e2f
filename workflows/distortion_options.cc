// The field-distortion options of fvm stitch and fvm calibrate --scan.

#include "workflows/distortion_options.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <cmath>

#include "core/input_error.h"
#include "workflows/field_distortion_file.h"

namespace fvm::workflows {

int DistortionOptions::Order() const {
  if (!file.empty()) return 0;
  if (order.empty() || order == "true") return 3;
  try {
    size_t used = 0;
    const int n = std::stoi(order, &used);
    if (used == order.size() && n >= 2 && n <= imaging::kMaxDistortionOrder) return n;
  } catch (const std::exception&) {
  }
  throw InputError(fmt::format("--distortion {}: give the polynomial order 2..{} (3 by default; orders 0 and 1 are the "
                               "field's linear part, which no overlap can tell from the stage steps)",
                               order, imaging::kMaxDistortionOrder));
}

std::optional<imaging::FieldDistortion> DistortionOptions::Known() const {
  if (file.empty()) return std::nullopt;
  imaging::FieldDistortion field = workflows::ReadFieldDistortion(file);
  if (field.Identity()) {
    throw InputError(file + ": the field has no terms (order 0): leave out --distortion-file to stitch rigidly");
  }
  return field;
}

void DistortionOptions::Check() const {
  if (identify && !file.empty()) {
    throw InputError("--distortion and --distortion-file: give one (identify a field, or use a saved one)");
  }
  if (!Requested() && !save.empty()) {
    throw InputError("--save-distortion " + save + ": there is no field to save; add --distortion");
  }
  if (!Requested() && !undistorted_dir.empty()) {
    throw InputError("--undistorted " + undistorted_dir + ": needs a field: add --distortion or --distortion-file");
  }
  Order();  // throws on a bad order
}

std::string DistortionText(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm) {
  const imaging::FieldDistortion& field = fit.field;
  Eigen::Vector2d where;
  const double largest = field.LargestDisplacementPx(&where);
  std::string text = fmt::format(
      "  field distortion ({}order {}): largest displacement {:.2f} px{} at pixel {:.0f}, {:.0f}; from {} "
      "correspondences in {} overlaps ({} without texture), {:.3f} px rms each (rigid: {:.3f} px)\n",
      identified ? "identified, " : "from the file, ", field.order, largest,
      pixel_mm > 0.0 ? fmt::format(" ({:.2f} um)", largest * pixel_mm * 1e3) : std::string(), where.x(), where.y(),
      fit.points, fit.pairs_used, fit.pairs_without_texture, fit.residual_rms_px, fit.rigid_rms_px);
  if (identified) {
    const std::vector<std::string>& names = imaging::FieldDistortionTermNames(field.order);
    std::vector<std::string> terms;
    for (size_t t = 0; t < names.size(); ++t) {
      const auto i = static_cast<Eigen::Index>(t);
      terms.push_back(fmt::format("{} {:+.3f} ({:.3f})", names[t], field.coefficients(i), std::sqrt(field.covariance(i, i))));
    }
    text += fmt::format("    terms, px (standard uncertainty): {}\n", fmt::join(terms, ", "));
    text += fmt::format("    field uncertainty {:.3f} px rms over the tile; {}\n", field.DisplacementSigmaPx(),
                        imaging::kFixedLinearPart);
    if (!fit.held_terms.empty()) {
      std::vector<std::string> held;
      for (int t : fit.held_terms) held.push_back(names[static_cast<size_t>(t)]);
      text += fmt::format("    held at 0: {}: {}\n", fmt::join(held, ", "), fit.held_reason);
    }
    if (!fit.tested_terms.empty() && fit.tested_terms_added) {
      std::vector<std::string> added;
      for (int t : fit.tested_terms) added.push_back(names[static_cast<size_t>(t)]);
      text += fmt::format("    added by evidence: {} (Wald statistic {:.1f} above 3 ln n = {:.1f}): the overlaps show the "
                          "own-axis cubic departing from radial symmetry\n",
                          fmt::join(added, ", "), fit.evidence_chi2, fit.evidence_threshold);
    }
  }
  return text;
}

nlohmann::ordered_json DistortionJson(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm) {
  nlohmann::ordered_json j = workflows::FieldDistortionJson(fit.field, pixel_mm);
  j["identified"] = identified;
  j["correspondences"] = fit.points;
  j["pairs_used"] = fit.pairs_used;
  j["pairs_without_texture"] = fit.pairs_without_texture;
  j["point_sigma_px"] = fit.point_sigma_px;
  j["rigid_rms_px"] = fit.rigid_rms_px;
  j["residual_rms_px"] = fit.residual_rms_px;
  j["pair_scatter_factor"] = fit.pair_scatter_factor;
  j["block_scatter_factor"] = fit.block_scatter_factor;
  if (!fit.held_terms.empty()) {  // stitching: the terms that act on a grid's overlaps as a stretch or shear
    nlohmann::ordered_json held = nlohmann::ordered_json::array();
    for (int t : fit.held_terms) held.push_back(imaging::FieldDistortionTermNames(fit.field.order)[static_cast<size_t>(t)]);
    j["held_terms"] = held;
    j["held"] = fit.held_reason;
  }
  if (!fit.tested_terms.empty()) {  // the non-radial own-axis cubic terms, tested (imaging/field_distortion_evidence.h)
    nlohmann::ordered_json tested = nlohmann::ordered_json::array();
    for (int t : fit.tested_terms) tested.push_back(imaging::FieldDistortionTermNames(fit.field.order)[static_cast<size_t>(t)]);
    j["evidence"] = {{"tested_terms", tested},
                     {"added", fit.tested_terms_added},
                     {"added_terms", fit.tested_terms_added ? tested : nlohmann::ordered_json::array()},
                     {"wald_chi2", fit.evidence_chi2},
                     {"threshold", fit.evidence_threshold}};
  }
  return j;
}

}  // namespace fvm::workflows
