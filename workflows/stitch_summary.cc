#include "workflows/stitch_summary.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

#include "workflows/distortion_options.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

Json FiniteOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json OverruledJson(const StitchedLayout& s) {
  const imaging::RegistrationResult& r = s.Registered().registration;
  Json out = Json::array();
  for (const auto& o : r.loops.overruled) {
    const imaging::PairRegistration& pair = r.pairs[static_cast<size_t>(o.pair)];
    out.push_back({{"a", s.files[static_cast<size_t>(pair.a)]},
                   {"b", s.files[static_cast<size_t>(pair.b)]},
                   {"registered_px", {o.registered_px.x(), o.registered_px.y()}},
                   {"predicted_px", {o.predicted_px.x(), o.predicted_px.y()}},
                   {"misclosure_sigma", o.misclosure_sigma},
                   {"replaced", o.replaced}});
  }
  return out;
}

Json StageModelJson(const imaging::RegistrationResult& r) {
  const imaging::TileGridSteps& model = r.stage;
  const auto component = [&](const Eigen::Vector2d& v, int k, int index) {
    return model.estimated[static_cast<size_t>(index)] ? Json(v(k)) : Json(nullptr);
  };
  return {{"east_step_px", component(model.east_px, 0, 0)},
          {"east_drift_px", component(model.east_px, 1, 1)},
          {"south_step_px", component(model.south_px, 1, 3)},
          {"south_drift_px", component(model.south_px, 0, 2)},
          {"nominal_east_px", {model.nominal_east_px.x(), model.nominal_east_px.y()}},
          {"nominal_south_px", {model.nominal_south_px.x(), model.nominal_south_px.y()}},
          {"repeatability_px",
           {model.repeatability_px.x() > 0.0 ? Json(model.repeatability_px.x()) : nullptr,
            model.repeatability_px.y() > 0.0 ? Json(model.repeatability_px.y()) : nullptr}},
          {"east_pairs", model.east_pairs},
          {"south_pairs", model.south_pairs},
          {"prior_sigma_px", r.stage_sigma_px},
          {"shared", {{"column_step_px", {r.stage_axes.column_step_px.x(), r.stage_axes.column_step_px.y()}},
                      {"row_step_px", {r.stage_axes.row_step_px.x(), r.stage_axes.row_step_px.y()}},
                      {"own_px", {r.stage_axes.own_px.x(), r.stage_axes.own_px.y()}}}},
          {"pairs_searched_again", r.pairs_searched_again}};
}

Json PairJson(const StitchedLayout& s, size_t k) {
  const imaging::PairRegistration& pair = s.Registered().registration.pairs[k];
  const Eigen::Vector2d d = pair.offset_px - pair.nominal_px;
  // Standard uncertainty per axis where the pair determines both; null along an axis it leaves to the stage.
  Json sigma = {nullptr, nullptr};
  if (pair.accepted && std::abs(pair.information.determinant()) > 0.0) {
    const Eigen::Matrix2d covariance = pair.information.inverse();
    sigma = {std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1))};
  }
  Json candidates = Json::array();
  for (const auto& c : pair.candidates) {
    candidates.push_back({{"dx_px", c.offset_px.x() - pair.nominal_px.x()},
                          {"dy_px", c.offset_px.y() - pair.nominal_px.y()},
                          {"peak", c.peak},
                          {"ncc", c.ncc},
                          {"overlap_px", c.overlap_px}});
  }
  return {{"a", s.files[static_cast<size_t>(pair.a)]},
          {"b", s.files[static_cast<size_t>(pair.b)]},
          {"dx_px", pair.accepted ? Json(d.x()) : nullptr},
          {"dy_px", pair.accepted ? Json(d.y()) : nullptr},
          {"sigma_px", sigma},
          {"quality", pair.quality},
          {"accepted", pair.accepted},
          {"overlap_ncc", FiniteOrNull(s.Registered().overlap_ncc[k].correlation.ncc)},
          {"searched", pair.searched},
          {"ambiguous", pair.ambiguous},
          {"unmoved", pair.unmoved},
          {"search_px", {pair.search_px.x(), pair.search_px.y()}},
          {"candidates", candidates},
          {"rejection", pair.accepted ? Json(nullptr) : Json(pair.rejection)}};
}

Json StitchJson(const StitchedLayout& s) {
  const StitchResult& placed = s.Registered();
  Json out;
  out["tiles"] = s.files.size();
  out["size_px"] = {s.width_px, s.height_px};
  out["nominal"] = placed.from_stage ? "stage" : "grid";
  out["pairs_accepted"] = placed.accepted;
  out["pairs_ambiguous"] = placed.ambiguous;
  out["mean_overlap_ncc"] = placed.ncc_pairs > 0 ? Json(placed.mean_overlap_ncc) : Json(nullptr);
  out["pairs_unresolved"] = placed.unresolved;
  out["unresolved_warning"] = placed.mostly_unresolved ? Json(placed.UnresolvedWarning()) : Json(nullptr);
  out["overruled"] = OverruledJson(s);
  out["loop_birge_ratio"] = placed.registration.loops.birge_ratio;
  out["loop_dof"] = placed.registration.loops.dof;
  out["stage_fallback"] = placed.at_stage_position;
  out["stage_along_one_axis"] = placed.stage_along_one_axis;
  out["without_neighbour"] = placed.without_neighbour;
  if (s.field) {
    out["distortion"] = DistortionJson(s.field->fit, s.field->identified, s.options.pixel_mm);
    out["distortion"]["overlap_ncc_before"] = FiniteOrNull(s.field->mean_overlap_ncc_before);
    out["distortion"]["overlap_ncc_after"] = FiniteOrNull(s.field->mean_overlap_ncc_after);
    out["distortion"]["pairs_registered_undistorted"] = s.field->pairs_registered_undistorted;
  }
  out["stage_model"] = StageModelJson(placed.registration);
  out["pairs"] = Json::array();
  for (size_t k = 0; k < placed.registration.pairs.size(); ++k) out["pairs"].push_back(PairJson(s, k));
  return out;
}

std::string StageModelText(const StitchedLayout& s) {
  const imaging::RegistrationResult& r = s.Registered().registration;
  const imaging::TileGridSteps& model = r.stage;
  if (!model.Any()) {
    return fmt::format("  stage model: not estimated ({} registered pairs; it needs {} per direction): the nominal "
                       "positions stand\n",
                       s.Registered().accepted, imaging::TileGridSteps::kMinPairs);
  }
  const auto value = [&](const Eigen::Vector2d& v, int k, int index) {
    return model.estimated[static_cast<size_t>(index)] ? fmt::format("{:+.2f}", v(k)) : std::string("nominal");
  };
  const auto repeat = [](double x) { return x > 0.0 ? fmt::format("{:.2f}", x) : std::string("unknown"); };
  return fmt::format("  stage model from {} east and {} south pairs: column step {} px (nominal {:.2f}), drift {} px "
                     "per column; row step {} px (nominal {:.2f}), drift {} px per row; repeatability {} x, {} y px; "
                     "{} pairs searched again within its tolerance\n",
                     model.east_pairs, model.south_pairs, value(model.east_px, 0, 0), model.nominal_east_px.x(),
                     value(model.east_px, 1, 1), value(model.south_px, 1, 3), model.nominal_south_px.y(),
                     value(model.south_px, 0, 2), repeat(model.repeatability_px.x()),
                     repeat(model.repeatability_px.y()), r.pairs_searched_again);
}

// The pairs a reader should look at: ambiguous ones the stage chose, rejected ones and why.
std::string PairsText(const StitchedLayout& s) {
  std::string text;
  for (const auto& pair : s.Registered().registration.pairs) {
    const std::string& a = s.files[static_cast<size_t>(pair.a)];
    const std::string& b = s.files[static_cast<size_t>(pair.b)];
    if (pair.accepted && pair.ambiguous) {
      text += fmt::format("  ambiguous {} - {}: another place matched almost as well (a repeating pattern); the "
                          "stage's prediction chose\n",
                          a, b);
    }
    if (!pair.accepted) text += fmt::format("  rejected {} - {}: {}\n", a, b, pair.rejection);
  }
  return text;
}

std::string UncertaintyText(const StitchedLayout& s) {
  const std::vector<Eigen::Vector2d>& sigmas = s.SigmaPx();
  double worst = 0.0, worst_any = 0.0;
  for (size_t i = 0; i < s.files.size(); ++i) {
    const double u = sigmas[i].maxCoeff();
    if (s.Registered().registration.positions.anchor[i] == 0) worst = std::max(worst, u);
    worst_any = std::max(worst_any, u);
  }
  std::string text =
      fmt::format("largest standard uncertainty of a registered tile against the first of its chain: {:.4f} px\n", worst);
  if (worst_any > worst) {
    text += fmt::format("largest standard uncertainty of a tile against the first tile: {:.2f} px (the stage's, where "
                        "no pair registered)\n",
                        worst_any);
  }
  return text;
}

std::string StitchText(const StitchedLayout& s) {
  const StitchResult& placed = s.Registered();
  std::string text = fmt::format(
      "{} tiles of {} x {} px, {} pairs, {} accepted (quality >= {}{}); nominal positions from the {}\n", s.files.size(),
      s.width_px, s.height_px, placed.registration.pairs.size(), placed.accepted, s.options.registration.min_quality,
      s.registered_undistorted ? ", on the tiles undistorted by the field" : "",
      placed.from_stage ? "stage" : "grid and overlap");
  text += StageModelText(s);
  if (placed.ncc_pairs > 0) {
    text += fmt::format("  mean overlap correlation of the {} neighbour pairs at these positions: {:.3f}\n",
                        placed.ncc_pairs, placed.mean_overlap_ncc);
  }
  text += PairsText(s);
  if (s.field) {
    text += DistortionText(s.field->fit, s.field->identified, s.options.pixel_mm);
    text += fmt::format("  mean overlap correlation of the undistorted tiles at their positions: {:.3f} (raw tiles, "
                        "rigid: {:.3f})\n",
                        s.field->mean_overlap_ncc_after, s.field->mean_overlap_ncc_before);
    if (s.field->pairs_registered_undistorted > 0) {
      text += fmt::format("  {} pairs the raw tiles did not register (the field shears their overlaps) registered on "
                          "the undistorted tiles; the field and the positions were identified again with them\n",
                          s.field->pairs_registered_undistorted);
    }
  }
  if (placed.accepted == 0) text += "  no pair registered: every tile stays at its nominal position\n";
  if (!placed.at_stage_position.empty()) {
    text += fmt::format("  at their stage positions (no good pair to an earlier tile): {}\n",
                        fmt::join(placed.at_stage_position, ", "));
  }
  if (!placed.without_neighbour.empty()) {
    text += fmt::format("  no neighbour beside them in the layout (holes on every side): registered through the corners "
                        "they share with their diagonal neighbours, or by the stage where none registers: {}\n",
                        fmt::join(placed.without_neighbour, ", "));
  }
  if (!placed.stage_along_one_axis.empty()) {
    text += fmt::format("  linked by pairs that fix one direction (parallel marks, traces, edges), placed along the "
                        "other by the stage's rows and columns (registered 0): {}\n",
                        fmt::join(placed.stage_along_one_axis, ", "));
  }
  return text + UncertaintyText(s);
}

}  // namespace

Summary Summarize(const StitchedLayout& stitched) {
  return {StitchJson(stitched), StitchText(stitched), StitchReport(stitched)};
}

}  // namespace fvm::workflows
