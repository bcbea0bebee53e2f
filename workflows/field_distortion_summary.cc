#include "workflows/field_distortion_summary.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "workflows/field_distortion_file.h"

namespace fvm::workflows {

std::string FieldDistortionFitText(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm) {
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

nlohmann::ordered_json FieldDistortionFitJson(const imaging::FieldDistortionFit& fit, bool identified, double pixel_mm) {
  nlohmann::ordered_json j = FieldDistortionJson(fit.field, pixel_mm);
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

}  // namespace fvm::workflows
