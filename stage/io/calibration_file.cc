#include "stage/io/calibration_file.h"

#include <fmt/core.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include "core/input_error.h"
#include "core/json_text.h"
#include "stage/error_terms.h"

namespace fvm::stage {
namespace {

using nlohmann::json;
using stage::ParameterLayout;

const char* RotationModelName(stage::RotationModel m) {
  return m == stage::RotationModel::kSmallAngle ? "small-angle" : "exact";
}

std::string StateName(ParameterLayout::State s) {
  switch (s) {
    case ParameterLayout::State::kFree: return "free";
    case ParameterLayout::State::kFixed: return "fixed";
    case ParameterLayout::State::kTied: return "tied";
  }
  return "?";
}

}  // namespace

json CalibrationToJson(const stage::IdentificationResult& result) {
  const stage::Calibration& cal = result.calibration;
  const ParameterLayout& layout = cal.layout;
  const stage::AxisChain& chain = layout.chain();
  json doc;
  doc["format"] = kCalibrationFormat;
  doc["model"] = cal.model;
  doc["chain"] = chain.code;
  std::string carriers;
  for (stage::Axis a : chain.squareness_carrier) carriers += stage::AxisLetter(a);
  doc["squareness_carrier"] = carriers;  // axis that carries xWy, xWz, yWz
  doc["rotation_model"] = RotationModelName(chain.rotation_model);
  // The tool point's offset from the last tool axis (machine tools): written when there is one, so that a
  // compensation (fvm correct) aims the same point the identification saw.
  if (!chain.tool_offset.isZero(0.0)) doc["tool_offset_mm"] = {chain.tool_offset.x(), chain.tool_offset.y(), chain.tool_offset.z()};
  for (int k = 0; k < 3; ++k) {
    doc["travel_mm"][std::string(1, "xyz"[k])] = {layout.travel()[static_cast<size_t>(k)].min, layout.travel()[static_cast<size_t>(k)].max};
  }
  for (int t = 0; t < stage::kNumErrorTerms; ++t) {
    const stage::TermSpec& spec = layout.term(t);
    if (!spec.present) continue;
    doc["terms"].push_back({{"term", stage::GetErrorTerm(t).vdi}, {"basis", stage::BasisName(spec.basis)}, {"order", spec.order}});
  }
  const Eigen::VectorXd u = cal.StandardUncertainty();
  for (const ParameterLayout::Coefficient& c : layout.coefficients()) {
    const stage::DisplayUnit unit = stage::UnitOf(c);
    const bool translation = std::string(unit.name) == "um";
    json p{{"name", c.name}, {"state", StateName(c.state)}, {"unit", translation ? "mm" : "rad"}};
    double value = c.value, uncertainty = 0.0;
    const int slot = layout.FreeIndexOf(c.name);
    if (slot >= 0) {
      value = cal.values[static_cast<size_t>(slot)];
      uncertainty = u.size() > slot ? u[slot] : 0.0;
    }
    if (c.state == ParameterLayout::State::kTied) {
      p["tied_to"] = c.tied_to;
      p["factor"] = c.value;
      value = c.value * cal.values[static_cast<size_t>(layout.FreeIndexOf(c.tied_to))];
    }
    p["value"] = value;
    p["u"] = uncertainty;
    p[std::string("value_") + unit.name] = value * unit.per_si;
    p[std::string("u_") + unit.name] = uncertainty * unit.per_si;
    doc["parameters"].push_back(p);
  }
  doc["fixed"] = json::array();
  for (const stage::FixedCoefficient& f : result.fixed) doc["fixed"].push_back({{"name", f.name}, {"reason", f.reason}});
  doc["free"] = layout.FreeNames();
  json cov = json::array(), corr = json::array();
  const Eigen::MatrixXd correlation = cal.Correlation();
  for (Eigen::Index i = 0; i < cal.covariance.rows(); ++i) {
    json crow = json::array(), rrow = json::array();
    for (Eigen::Index j = 0; j < cal.covariance.cols(); ++j) {
      crow.push_back(cal.covariance(i, j));
      rrow.push_back(correlation(i, j));
    }
    cov.push_back(crow);
    corr.push_back(rrow);
  }
  doc["covariance"] = cov;
  doc["correlation"] = corr;
  doc["condition_number"] = result.condition_number;
  doc["sigma_mm"] = cal.sigma_mm;
  // What the model cannot take at a point (calibration.h), for fvm correct's u; written where something estimated it.
  if (!cal.unmodelled_mm.isZero(0.0)) doc["unmodelled_mm"] = {cal.unmodelled_mm.x(), cal.unmodelled_mm.y(), cal.unmodelled_mm.z()};
  if (cal.frame_reference) {
    const Eigen::Vector3d& r = *cal.frame_reference;
    doc["frame_reference_mm"] = {r.x(), r.y(), r.z()};  // the first tile whose view the part frame is (stitched_frame.h)
  }
  doc["identification"] = {{"centres", result.residuals.size()}, {"mean_um", result.residual_summary.mean_um()},
                           {"rms_um", result.residual_summary.rms_um()},       {"max_um", result.residual_summary.max_um()},
                           {"iterations", result.iterations},     {"converged", result.converged}};
  return doc;
}

stage::Calibration ReadCalibration(const std::filesystem::path& path) {
  const json doc = ReadJsonFile(path, fmt::format("a calibration file is written by 'fvm calibrate ... -o {}'",
                                                  path.filename().string()));
  const auto fail = [&](const std::string& what) {
    return InputError(fmt::format("{}: {}; write it with 'fvm calibrate ... -o {}'", path.string(), what, path.filename().string()));
  };
  try {
    if (doc.value("format", "") != kCalibrationFormat) throw fail(std::string("'format' is not ") + kCalibrationFormat);
    stage::AxisChain chain = stage::AxisChain::Parse(doc.at("chain").get<std::string>());
    const std::string carriers = doc.at("squareness_carrier").get<std::string>();
    if (carriers.size() != 3) throw fail("'squareness_carrier' must name three axes");
    for (size_t w = 0; w < 3; ++w) {
      const size_t axis = std::string("xyz").find(carriers[w]);
      if (axis == std::string::npos) throw fail("'squareness_carrier' must use x, y, z");
      chain.squareness_carrier[w] = static_cast<stage::Axis>(axis);
    }
    chain.rotation_model = doc.value("rotation_model", "small-angle") == "exact" ? stage::RotationModel::kExact
                                                                                  : stage::RotationModel::kSmallAngle;
    if (doc.contains("tool_offset_mm")) {
      const json& t = doc["tool_offset_mm"];
      if (!t.is_array() || t.size() != 3) throw fail("'tool_offset_mm' must be three numbers [x, y, z] in mm");
      for (size_t k = 0; k < 3; ++k) {
        if (!t[k].is_number() || !std::isfinite(t[k].get<double>()) || std::abs(t[k].get<double>()) > 1e5) {
          throw fail(fmt::format("'tool_offset_mm'[{}] must be a finite number of mm (at most 100 m)", k));
        }
        chain.tool_offset[static_cast<Eigen::Index>(k)] = t[k].get<double>();
      }
    }
    std::array<stage::Travel, 3> travel;
    for (int k = 0; k < 3; ++k) {
      const json& t = doc.at("travel_mm").at(std::string(1, "xyz"[k]));
      travel[static_cast<size_t>(k)] = stage::Travel{t.at(0).get<double>(), t.at(1).get<double>()};
    }
    ParameterLayout layout(chain, travel);
    for (const json& t : doc.at("terms")) {
      const auto basis = stage::ParseBasis(t.at("basis").get<std::string>());
      if (!basis) throw fail("unknown basis in 'terms'");
      layout.SetTerm(t.at("term").get<std::string>(), *basis, t.at("order").get<int>());
    }
    // Coefficients the file does not list were dropped from the model.
    std::set<std::string> listed;
    for (const json& p : doc.at("parameters")) listed.insert(p.at("name").get<std::string>());
    std::vector<std::string> all;
    for (const auto& c : layout.coefficients()) all.push_back(c.name);
    for (const std::string& name : all) {
      if (!listed.contains(name)) layout.Drop(name);
    }
    std::map<std::string, double> free_values;
    const json& parameters = doc.at("parameters");
    for (size_t i = 0; i < parameters.size(); ++i) {
      const json& p = parameters.at(i);
      const std::string name = p.at("name").get<std::string>();
      // Errors here name the entry, so a hand edit can be found and undone.
      const std::string key = fmt::format("'parameters'[{}] ({})", i, name);
      const auto finite = [&](const char* field) {
        const double v = p.at(field).get<double>();
        if (!std::isfinite(v)) throw fail(fmt::format("{}: '{}' is not a finite number", key, field));
        return v;
      };
      const std::string state = p.at("state").get<std::string>();
      if (layout.FindCoefficient(name) < 0) {
        throw fail(fmt::format("{}: no such coefficient in the model the 'terms' describe", key));
      }
      try {
        if (state == "fixed") layout.Fix(name, finite("value"));
        else if (state == "tied") layout.Tie(name, p.at("tied_to").get<std::string>(), finite("factor"));
        else if (state == "free") free_values[name] = finite("value");
        else throw fail(fmt::format("{}: 'state' is '{}', not free, fixed or tied", key, state));
      } catch (const std::invalid_argument& e) {
        throw fail(fmt::format("{}: {}", key, e.what()));
      }
    }
    stage::Calibration cal{doc.value("model", ""), layout, {}, {}, doc.value("sigma_mm", 0.0), std::nullopt, {}};
    for (const std::string& name : layout.FreeNames()) cal.values.push_back(free_values.at(name));
    const int n = layout.NumFree();
    cal.covariance = Eigen::MatrixXd::Zero(n, n);
    const json& cov = doc.at("covariance");
    if (static_cast<int>(cov.size()) != n) throw fail(fmt::format("'covariance' has {} rows for {} free parameters", cov.size(), n));
    for (int i = 0; i < n; ++i) {
      if (static_cast<int>(cov.at(static_cast<size_t>(i)).size()) != n) {
        throw fail(fmt::format("'covariance' row {} has {} entries for {} free parameters", i, cov.at(static_cast<size_t>(i)).size(), n));
      }
    }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) cal.covariance(i, j) = cov.at(static_cast<size_t>(i)).at(static_cast<size_t>(j)).get<double>();
    if (doc.contains("frame_reference_mm")) {
      const json& r = doc.at("frame_reference_mm");
      if (!r.is_array() || r.size() != 3) throw fail("'frame_reference_mm' is not three numbers (x, y, z in mm)");
      cal.frame_reference = Eigen::Vector3d(r.at(0).get<double>(), r.at(1).get<double>(), r.at(2).get<double>());
      if (!cal.frame_reference->allFinite()) throw fail("'frame_reference_mm' is not finite");
    }
    if (doc.contains("unmodelled_mm")) {
      const json& m = doc.at("unmodelled_mm");
      if (!m.is_array() || m.size() != 3) throw fail("'unmodelled_mm' is not three numbers (x, y, z in mm)");
      for (size_t k = 0; k < 3; ++k) {
        const double v = m.at(k).get<double>();
        if (!std::isfinite(v) || v < 0.0) throw fail(fmt::format("'unmodelled_mm'[{}] is not a finite standard deviation (>= 0 mm)", k));
        cal.unmodelled_mm[static_cast<Eigen::Index>(k)] = v;
      }
    }
    return cal;
  } catch (const json::exception& e) {
    throw fail(std::string("missing or malformed key (") + e.what() + ")");
  } catch (const std::invalid_argument& e) {
    throw fail(e.what());
  } catch (const std::out_of_range& e) {
    throw fail(std::string("inconsistent parameters (") + e.what() + ")");
  }
}

bool IsMachineModelFile(const std::filesystem::path& path) {
  nlohmann::json doc;
  try {
    doc = ReadJsonFile(path);
  } catch (const InputError&) {
    return false;
  }
  return doc.is_object() && (doc.contains("instrument_pose") || doc.contains("tool_offset_mm"));
}

}  // namespace fvm::stage
