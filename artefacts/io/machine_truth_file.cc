#include "artefacts/io/machine_truth_file.h"

#include <fmt/core.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "stage/error_terms.h"

namespace fvm::artefacts {
namespace {

using nlohmann::json;

// Sanity bounds: errors of a machine tool are micrometres and microradians; 10 mm or 10 mrad means wrong units.
constexpr double kMaxTranslationMm = 10.0;
constexpr double kMaxAngleRad = 0.01;

double Number(const json& value, const std::string& where) {
  if (!value.is_number()) throw InputError(fmt::format("{}: '{}' is not a number", where, value.dump()));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw InputError(fmt::format("{}: {} is not a finite number", where, v));
  return v;
}

TermTruth ReadTerm(const json& spec, const std::string& where, bool squareness) {
  if (!spec.is_object()) {
    throw InputError(fmt::format("{}: give an object {{\"poly\": [...], \"sine\": {{...}}}}, not {}", where,
                                 spec.dump().substr(0, 40)));
  }
  TermTruth term;
  for (const auto& [key, value] : spec.items()) {
    if (key != "poly" && key != "sine") {
      throw InputError(fmt::format("{}: unknown key '{}'; a term has \"poly\" and optionally \"sine\"", where, key));
    }
  }
  if (!spec.contains("poly")) throw InputError(fmt::format("{}: no \"poly\" coefficients (give [0] for none)", where));
  const json& poly = spec.at("poly");
  if (!poly.is_array() || poly.empty() || poly.size() > 4) {
    throw InputError(fmt::format("{}: \"poly\" must be an array of 1 to 4 coefficients (constant .. cubic in q - min, "
                                 "mm), not {}",
                                 where, poly.dump().substr(0, 60)));
  }
  if (squareness && poly.size() != 1) {
    throw InputError(fmt::format("{}: a squareness term is one angle: \"poly\": [rad]", where));
  }
  for (size_t i = 0; i < poly.size(); ++i) term.poly[i] = Number(poly[i], fmt::format("{}: poly[{}]", where, i));
  if (spec.contains("sine")) {
    if (squareness) throw InputError(fmt::format("{}: a squareness term is one angle and takes no sine", where));
    const json& sine = spec.at("sine");
    if (!sine.is_object()) throw InputError(fmt::format("{}: \"sine\" must be an object {{amplitude, pitch_mm, phase_rad}}", where));
    for (const auto& [key, value] : sine.items()) {
      if (key != "amplitude" && key != "pitch_mm" && key != "phase_rad") {
        throw InputError(fmt::format("{}: sine: unknown key '{}'; use amplitude, pitch_mm, phase_rad", where, key));
      }
    }
    for (const char* key : {"amplitude", "pitch_mm"}) {
      if (!sine.contains(key)) throw InputError(fmt::format("{}: sine: '{}' is missing", where, key));
    }
    term.sine_amplitude = Number(sine.at("amplitude"), where + ": sine amplitude");
    term.sine_pitch_mm = Number(sine.at("pitch_mm"), where + ": sine pitch_mm");
    if (sine.contains("phase_rad")) term.sine_phase_rad = Number(sine.at("phase_rad"), where + ": sine phase_rad");
    if (!(term.sine_pitch_mm > 0.0)) {
      throw InputError(fmt::format("{}: sine pitch_mm = {} must be positive (mm per period)", where, term.sine_pitch_mm));
    }
  }
  return term;
}

std::optional<double> LargestOnTravel(const TermTruth& term, double travel, double bound) {
  constexpr int kSamples = 2000;
  for (int i = 0; i <= kSamples; ++i) {
    const double v = term.Value(travel * i / kSamples);
    if (!(std::abs(v) <= bound)) return v;
  }
  return std::nullopt;
}

}  // namespace

MachineTruth ParseMachineTruth(std::string_view json_text, const std::string& name, const Workspace& ws) {
  ws.Check();
  const json root = ParseJsonText(json_text, name);
  if (!root.is_object() || !root.contains("terms") || !root.at("terms").is_object()) {
    throw InputError(fmt::format("{}: expected an object with \"terms\": {{\"xTx\": {{\"poly\": [...]}}, ...}} "
                                 "(format: docs/tutorials/machine-tool.md)",
                                 name));
  }
  MachineTruth truth;
  truth.workspace = ws;
  if (root.contains("workspace")) {
    const json& w = root.at("workspace");
    if (!w.is_object() || !w.contains("min_mm") || !w.at("min_mm").is_array() || w.at("min_mm").size() != 3) {
      throw InputError(fmt::format("{}: \"workspace\" must hold \"min_mm\": [x, y, z]", name));
    }
    for (int k = 0; k < 3; ++k) {
      const double min = Number(w.at("min_mm")[static_cast<size_t>(k)], name + ": workspace min_mm");
      if (std::abs(min - ws.min[k]) > 1e-9) {
        throw InputError(fmt::format("{}: the terms are written for the {} origin {} mm, the machine's is {} mm; the "
                                     "polynomials are in q - origin: give the same origin (--machine ...@X0,Y0,Z0)",
                                     name, "xyz"[k], min, ws.min[k]));
      }
    }
  }
  std::array<bool, stage::kNumErrorTerms> seen{};
  for (const auto& [key, spec] : root.at("terms").items()) {
    const std::optional<int> index = stage::FindErrorTerm(key);
    if (!index) {
      throw InputError(fmt::format("{}: unknown error term '{}'; use VDI 2617-3 names (xTx, xTy, ..., zRz, xWy, xWz, "
                                   "yWz) or ISO 230-1 aliases (EXX, EYX, ...)",
                                   name, key));
    }
    const stage::ErrorTerm& info = stage::GetErrorTerm(*index);
    const std::string where = fmt::format("{}: term {}", name, key);
    if (seen[static_cast<size_t>(*index)]) {
      throw InputError(fmt::format("{} is given twice (as {} or {}); give each term once", where, info.vdi, info.iso));
    }
    seen[static_cast<size_t>(*index)] = true;
    const bool squareness = info.kind == stage::ErrorKind::kSquareness;
    TermTruth term = ReadTerm(spec, where, squareness);
    const bool translation = info.kind == stage::ErrorKind::kTranslation;
    const double bound = translation ? kMaxTranslationMm : kMaxAngleRad;
    const int k = static_cast<int>(info.axis);
    if (const auto v = LargestOnTravel(term, squareness ? 0.0 : ws.max[k] - ws.min[k], bound)) {
      throw InputError(fmt::format("{} reaches {} {} on its travel, beyond {} {}: values are mm and rad (um or urad "
                                   "given?)",
                                   where, *v, translation ? "mm" : "rad", bound, translation ? "mm" : "rad"));
    }
    truth.terms[static_cast<size_t>(*index)] = term;
  }
  return truth;
}

MachineTruth ReadMachineTruth(const std::filesystem::path& path, const Workspace& ws) {
  return ParseMachineTruth(ReadFileBytes(path, std::size_t{16} << 20), path.string(), ws);
}

std::string MachineTruthJson(const MachineTruth& truth) {
  json root;
  root["workspace"] = {{"min_mm", {truth.workspace.min.x(), truth.workspace.min.y(), truth.workspace.min.z()}},
                       {"max_mm", {truth.workspace.max.x(), truth.workspace.max.y(), truth.workspace.max.z()}}};
  json terms = json::object();
  for (int t = 0; t < stage::kNumErrorTerms; ++t) {
    const TermTruth& term = truth.terms[static_cast<size_t>(t)];
    const stage::ErrorTerm& info = stage::GetErrorTerm(t);
    json spec;
    if (info.kind == stage::ErrorKind::kSquareness) {
      spec["poly"] = {term.poly[0]};
    } else {
      spec["poly"] = term.poly;
      if (term.sine_pitch_mm > 0.0) {
        spec["sine"] = {{"amplitude", term.sine_amplitude},
                        {"pitch_mm", term.sine_pitch_mm},
                        {"phase_rad", term.sine_phase_rad}};
      }
    }
    terms[std::string(info.vdi)] = spec;
  }
  root["terms"] = terms;
  return root.dump(2);
}

}  // namespace fvm::artefacts
