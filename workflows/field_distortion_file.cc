#include "workflows/field_distortion_file.h"

#include <fmt/core.h>

#include <cmath>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm::workflows {

nlohmann::ordered_json FieldDistortionJson(const imaging::FieldDistortion& field, double pixel_mm) {
  nlohmann::ordered_json j;
  j["format"] = "fvm-field-distortion";
  j["version"] = 1;
  j["width_px"] = field.width_px;
  j["height_px"] = field.height_px;
  j["order"] = field.order;
  j["terms"] = nlohmann::ordered_json::array();
  if (field.Identity()) return j;
  const std::vector<std::string>& names = imaging::FieldDistortionTermNames(field.order);
  const bool has_u = field.covariance.size() != 0;
  for (size_t t = 0; t < names.size(); ++t) {
    const auto i = static_cast<Eigen::Index>(t);
    j["terms"].push_back({{"name", names[t]},
                          {"value_px", field.coefficients(i)},
                          {"u_px", has_u ? nlohmann::ordered_json(std::sqrt(field.covariance(i, i))) : nullptr}});
  }
  if (has_u) {
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    for (Eigen::Index r = 0; r < field.covariance.rows(); ++r) {
      nlohmann::ordered_json row = nlohmann::ordered_json::array();
      for (Eigen::Index c = 0; c < field.covariance.cols(); ++c) row.push_back(field.covariance(r, c));
      rows.push_back(row);
    }
    j["covariance_px2"] = rows;
  }
  j["fixed"] = imaging::kFixedLinearPart;
  Eigen::Vector2d where;
  const double largest = field.LargestDisplacementPx(&where);
  j["largest_displacement_px"] = largest;
  j["largest_displacement_at_px"] = {where.x(), where.y()};
  if (pixel_mm > 0.0) j["largest_displacement_um"] = largest * pixel_mm * 1e3;
  j["sigma_px"] = has_u ? nlohmann::ordered_json(field.DisplacementSigmaPx()) : nullptr;
  return j;
}

void WriteFieldDistortion(const std::string& path, const imaging::FieldDistortion& field, double pixel_mm) {
  WriteFileAtomically(path, FieldDistortionJson(field, pixel_mm).dump(2) + "\n");
}

imaging::FieldDistortion ReadFieldDistortion(const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFileBytes(path, std::size_t{1} << 24));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: not a field distortion (JSON): {}", path, e.what()));
  }
  imaging::FieldDistortion field;
  try {
    if (j.value("format", std::string()) != "fvm-field-distortion") {
      throw InputError(fmt::format("{}: not a field distortion: \"format\" must be \"fvm-field-distortion\" (write one "
                                   "with fvm stitch --distortion --save-distortion)", path));
    }
    field.width_px = j.at("width_px").get<int>();
    field.height_px = j.at("height_px").get<int>();
    field.order = j.at("order").get<int>();
    if (field.order == 0) return field;
    const std::vector<std::string>& names = imaging::FieldDistortionTermNames(field.order);
    const auto& terms = j.at("terms");
    if (terms.size() != names.size()) {
      throw InputError(fmt::format("{}: order {} has {} terms, the file lists {}", path, field.order, names.size(),
                                   terms.size()));
    }
    field.coefficients.resize(static_cast<Eigen::Index>(names.size()));
    for (size_t t = 0; t < names.size(); ++t) {
      if (terms[t].at("name").get<std::string>() != names[t]) {
        throw InputError(fmt::format("{}: term {} is \"{}\", order {} expects \"{}\" there", path, t + 1,
                                     terms[t].at("name").get<std::string>(), field.order, names[t]));
      }
      field.coefficients(static_cast<Eigen::Index>(t)) = terms[t].at("value_px").get<double>();
    }
    if (j.contains("covariance_px2")) {
      const auto& rows = j.at("covariance_px2");
      const auto k = static_cast<Eigen::Index>(names.size());
      if (rows.size() != names.size()) throw InputError(path + ": covariance_px2 does not match the terms");
      field.covariance.resize(k, k);
      for (Eigen::Index r = 0; r < k; ++r) {
        if (rows[static_cast<size_t>(r)].size() != names.size()) throw InputError(path + ": covariance_px2 is not square");
        for (Eigen::Index c = 0; c < k; ++c) field.covariance(r, c) = rows[static_cast<size_t>(r)][static_cast<size_t>(c)].get<double>();
      }
    }
    field.Check();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: a field distortion needs width_px, height_px, order and terms [{{name, "
                                 "value_px}}]: {}", path, e.what()));
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
  if (!field.coefficients.allFinite()) throw InputError(path + ": a coefficient is not a finite number");
  return field;
}

}  // namespace fvm::workflows
