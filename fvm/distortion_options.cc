// The field-distortion options of fvm stitch and fvm calibrate --scan.

#include "fvm/distortion_options.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <cmath>

#include "core/input_error.h"
#include "workflows/field_distortion_file.h"

namespace fvm::cli {

int DistortionArgs::Order() const {
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

std::optional<imaging::FieldDistortion> DistortionArgs::Known() const {
  if (file.empty()) return std::nullopt;
  imaging::FieldDistortion field = workflows::ReadFieldDistortion(file);
  if (field.Identity()) {
    throw InputError(file + ": the field has no terms (order 0): leave out --distortion-file to stitch rigidly");
  }
  return field;
}

void DistortionArgs::Check() const {
  if (order_option && order_option->count() > 0 && !file.empty()) {
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

void AddDistortionOptions(CLI::App* sub, DistortionArgs* args, bool undistorted_dir) {
  args->order_option =
      sub->add_option("--distortion", args->order,
                      "identify the objective's field distortion from the overlaps, jointly with the positions: "
                      "radial (k1, k2), tangential (p1, p2) and polynomial terms up to ORDER (2-6, default 3) in the "
                      "tile's pixel coordinates; its linear part (scale, shear, turn) cannot be told from the stage "
                      "steps and stays fixed at 0. Refuses what the overlaps cannot determine (a strip in one "
                      "direction, texture-free overlaps, too high an order), naming the terms")
          ->expected(0, 1);
  sub->add_option("--distortion-file", args->file,
                  "take the field saved by --save-distortion (the same objective): positions only");
  sub->add_option("--save-distortion", args->save, "write the field (JSON: terms with u, covariance) for later scans");
  if (undistorted_dir) {
    sub->add_option("--undistorted", args->undistorted_dir,
                    "write each tile resampled without the field into this directory: same name, size and pixel "
                    "type (float tiles: NaN where the raw tile does not reach; integer tiles: the nearest edge pixel)");
  }
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
  return j;
}

}  // namespace fvm::cli
