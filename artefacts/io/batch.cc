#include "artefacts/io/batch.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/file_io.h"
#include "core/json_text.h"
#include "core/input_error.h"

namespace fvm::artefacts {
namespace {

constexpr std::string_view kStitchedSuffix = ".stitched.csv";
constexpr std::string_view kFreeSuffix = ".free.csv";
constexpr std::string_view kRolesFile = "batch.json";

bool EndsWith(const std::string& s, std::string_view suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}


// Calottes of a placement closer together than this in x and y cannot show a stage error: the stage moves between
// them by less than ten times a centre's noise (about 1 um). Such a placement is a constant or copied column, or
// numbers in the wrong unit, not a measurement.
constexpr double kMinPlacementSpanMm = 0.01;

// Throws naming the file when the centres of an export of two or more calottes collapse to one point in x and y.
void CheckSpan(const CentreExport& from) {
  if (from.centres.size() < 2) return;
  Eigen::Vector2d lo = from.centres.front().position.head<2>(), hi = lo;
  for (const CentreRecord& c : from.centres) {
    lo = lo.cwiseMin(c.position.head<2>());
    hi = hi.cwiseMax(c.position.head<2>());
  }
  const Eigen::Vector2d span = hi - lo;
  if (span.maxCoeff() < kMinPlacementSpanMm) {
    throw InputError(fmt::format("{}: its {} calottes span {:.3g} um in x and {:.3g} um in y, less than {} um: they "
                                 "cannot show a stage error; check that x and y hold each calotte's centre in mm "
                                 "(not a constant or copied column)",
                                 from.source, from.centres.size(), span.x() * 1e3, span.y() * 1e3,
                                 kMinPlacementSpanMm * 1e3));
  }
}

// "FILE:LINE" for a record read from a file, "FILE" for one found in a surface.
std::string Where(const CentreExport& from, const CentreRecord& record) {
  return record.line > 0 ? fmt::format("{}:{}", from.source, record.line) : from.source;
}

}  // namespace

Placement PairCentreExports(const std::string& name, const CentreExport& stitched, const CentreExport& free) {
  for (const CentreRecord& c : stitched.centres) {
    if (free.Find(c.id) == nullptr) {
      throw InputError(fmt::format("{}: calotte {} is not in {}; a placement needs every calotte measured with "
                                   "and without stitching: add it there or delete it here",
                                   Where(stitched, c), c.id, free.source));
    }
  }
  for (const CentreRecord& c : free.centres) {
    if (stitched.Find(c.id) == nullptr) {
      throw InputError(fmt::format("{}: calotte {} is not in {}; a placement needs every calotte measured with "
                                   "and without stitching: add it there or delete it here",
                                   Where(free, c), c.id, stitched.source));
    }
  }
  CheckSpan(stitched);
  CheckSpan(free);
  Placement placement;
  placement.name = name;
  const bool timed = std::all_of(free.centres.begin(), free.centres.end(),
                                 [](const CentreRecord& c) { return c.t_s.has_value(); });
  for (const CentreRecord& c : stitched.centres) {
    const CentreRecord& f = *free.Find(c.id);
    placement.ids.push_back(c.id);
    placement.stitched.push_back(c.position);
    placement.free.push_back(f.position);
    if (timed) placement.t_s.push_back(*f.t_s);
  }
  return placement;
}

namespace {

// The stitched file defines the calottes and their order; the free file must hold exactly the same ones.
Placement ReadPlacement(const std::string& name, const std::filesystem::path& stitched_path,
                        const std::filesystem::path& free_path) {
  return PairCentreExports(name, ReadCentreExport(stitched_path), ReadCentreExport(free_path));
}

std::vector<std::string> ReadNameList(const nlohmann::json& roles, const char* key, const std::string& where) {
  std::vector<std::string> names;
  const auto it = roles.find(key);
  if (it == roles.end()) return names;
  if (!it->is_array()) {
    throw InputError(fmt::format("{}: \"{}\" must be a list of placement names, e.g. [\"x\", \"y\"]", where, key));
  }
  for (const nlohmann::json& entry : *it) {
    if (!entry.is_string()) {
      throw InputError(fmt::format("{}: \"{}\" holds {}, not a placement name; write names as strings", where, key,
                                   entry.dump()));
    }
    const std::string name = entry.get<std::string>();
    if (std::find(names.begin(), names.end(), name) != names.end()) {
      throw InputError(fmt::format("{}: \"{}\" names placement '{}' twice; list it once", where, key, name));
    }
    names.push_back(name);
  }
  return names;
}

// Roles decide which data may enter the fit; a typo here would silently leak validation data into it, so
// everything unexpected is an error rather than a default.
void ReadRoles(const std::filesystem::path& path, Batch& batch) {
  const std::string where = path.string();
  const nlohmann::json roles =
      ReadJsonFile(path, "write {\"identify\": [...], \"validate\": [...], \"lens\": \"5x\"}", std::size_t{1} << 24);
  if (!roles.is_object()) {
    throw InputError(fmt::format("{}: expected an object {{\"identify\": [...], \"validate\": [...], \"lens\": "
                                 "\"5x\"}}, found {}",
                                 where, roles.type_name()));
  }
  for (const auto& [key, value] : roles.items()) {
    if (key != "identify" && key != "validate" && key != "lens") {
      throw InputError(fmt::format("{}: unknown key \"{}\"; the keys are identify, validate and lens", where, key));
    }
  }
  const bool has_identify = roles.contains("identify");
  std::vector<std::string> identify = ReadNameList(roles, "identify", where);
  std::vector<std::string> validate = ReadNameList(roles, "validate", where);
  AssignBatchRoles(batch, has_identify ? std::optional(std::move(identify)) : std::nullopt, std::move(validate), where);
  if (const auto lens = roles.find("lens"); lens != roles.end()) {
    if (!lens->is_string()) {
      throw InputError(fmt::format("{}: \"lens\" must be a string such as \"5x\", found {}", where, lens->dump()));
    }
    batch.lens = lens->get<std::string>();
  }
  batch.has_roles = true;
}

}  // namespace

const Placement& Batch::Get(const std::string& name) const {
  for (const Placement& p : placements) {
    if (p.name == name) return p;
  }
  std::vector<std::string> names;
  for (const Placement& p : placements) names.push_back(p.name);
  throw InputError(fmt::format("{}: no placement '{}'; the placements are {}", dir.string(), name, fmt::join(names, ", ")));
}

Batch ReadBatch(const std::filesystem::path& dir) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) {
    throw InputError(fmt::format("{}: not a batch directory ({}); give the directory that holds the "
                                 "<placement>{} / <placement>{} pairs",
                                 dir.string(), std::filesystem::exists(dir) ? "not a directory" : "no such directory",
                                 kStitchedSuffix, kFreeSuffix));
  }
  std::set<std::string> stitched_names, free_names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string file = entry.path().filename().string();
    if (EndsWith(file, kStitchedSuffix)) stitched_names.insert(file.substr(0, file.size() - kStitchedSuffix.size()));
    if (EndsWith(file, kFreeSuffix)) free_names.insert(file.substr(0, file.size() - kFreeSuffix.size()));
  }
  for (const std::string& name : stitched_names) {
    if (!free_names.contains(name)) {
      throw InputError(fmt::format("{}: has no partner {}; measure the placement without stitching too, or move "
                                   "the file out of the batch",
                                   (dir / (name + std::string(kStitchedSuffix))).string(),
                                   (dir / (name + std::string(kFreeSuffix))).string()));
    }
  }
  for (const std::string& name : free_names) {
    if (!stitched_names.contains(name)) {
      throw InputError(fmt::format("{}: has no partner {}; measure the placement with stitching too, or move the "
                                   "file out of the batch",
                                   (dir / (name + std::string(kFreeSuffix))).string(),
                                   (dir / (name + std::string(kStitchedSuffix))).string()));
    }
  }
  if (stitched_names.empty()) {
    throw InputError(fmt::format("{}: no placements; a batch holds pairs <placement>{} (stitched) and "
                                 "<placement>{} (stitching-free)",
                                 dir.string(), kStitchedSuffix, kFreeSuffix));
  }

  Batch batch;
  batch.dir = dir;
  for (const std::string& name : stitched_names) {  // std::set: sorted by name
    batch.placements.push_back(ReadPlacement(name, dir / (name + std::string(kStitchedSuffix)),
                                             dir / (name + std::string(kFreeSuffix))));
  }
  ApplyBatchRoles(dir, batch);
  return batch;
}

void AssignBatchRoles(Batch& batch, std::optional<std::vector<std::string>> identify, std::vector<std::string> validate,
                      const std::string& where) {
  std::vector<std::string> all;
  for (const Placement& p : batch.placements) all.push_back(p.name);
  batch.identify = identify.value_or(std::vector<std::string>{});
  batch.validate = std::move(validate);
  for (const auto* list : {&batch.identify, &batch.validate}) {
    for (const std::string& name : *list) {
      if (std::find(all.begin(), all.end(), name) == all.end()) {
        throw InputError(fmt::format("{}: placement '{}' has no {}{} / {}{} pair here; the placements are {}", where,
                                     name, name, kStitchedSuffix, name, kFreeSuffix, fmt::join(all, ", ")));
      }
    }
  }
  for (const std::string& name : batch.validate) {
    if (std::find(batch.identify.begin(), batch.identify.end(), name) != batch.identify.end()) {
      throw InputError(fmt::format("{}: placement '{}' is both in \"identify\" and \"validate\"; validation data "
                                   "must not enter the fit: keep it in one list",
                                   where, name));
    }
  }
  if (!identify) {
    // Everything not held out for validation identifies, as without batch.json.
    for (const std::string& name : all) {
      if (std::find(batch.validate.begin(), batch.validate.end(), name) == batch.validate.end()) {
        batch.identify.push_back(name);
      }
    }
  }
  if (batch.identify.empty()) {
    throw InputError(fmt::format("{}: no placement is left to identify the model; list at least one in "
                                 "\"identify\"",
                                 where));
  }
}

void ApplyBatchRoles(const std::filesystem::path& dir, Batch& batch) {
  const std::filesystem::path roles = dir / kRolesFile;
  if (std::filesystem::exists(roles)) {
    ReadRoles(roles, batch);
  } else {
    for (const Placement& p : batch.placements) batch.identify.push_back(p.name);
  }
}

void WriteBatch(const std::filesystem::path& dir, const Batch& batch) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) {
    throw InputError(fmt::format("{}: cannot create the batch directory ({}); check the path and permissions",
                                 dir.string(), error.message()));
  }
  for (const Placement& p : batch.placements) {
    // Malformed placements are a bug of the caller, not of the user's files.
    if (p.name.empty() || p.name.find('/') != std::string::npos) {
      throw std::invalid_argument("WriteBatch: placement name '" + p.name + "' cannot be a file name");
    }
    if (p.stitched.size() != p.ids.size() || p.free.size() != p.ids.size() ||
        (!p.t_s.empty() && p.t_s.size() != p.ids.size())) {
      throw std::invalid_argument("WriteBatch: placement '" + p.name + "' has ids, centres and times of unequal size");
    }
    CentreExport stitched, free;
    stitched.comments = {fmt::format("placement {}: stitched (reference) calotte centres, mm", p.name)};
    free.comments = {fmt::format("placement {}: stitching-free calotte centres, mm{}", p.name,
                                 p.t_s.empty() ? "" : "; t in s since the measurement started")};
    for (size_t i = 0; i < p.ids.size(); ++i) {
      CentreRecord s, f;
      s.id = f.id = p.ids[i];
      s.position = p.stitched[i];
      f.position = p.free[i];
      if (!p.t_s.empty()) f.t_s = p.t_s[i];
      stitched.centres.push_back(s);
      free.centres.push_back(f);
    }
    WriteCentreExport(dir / (p.name + std::string(kStitchedSuffix)), stitched);
    WriteCentreExport(dir / (p.name + std::string(kFreeSuffix)), free);
  }
  if (batch.has_roles) {
    nlohmann::json roles = {{"identify", batch.identify}, {"validate", batch.validate}};
    if (!batch.lens.empty()) roles["lens"] = batch.lens;
    WriteFileAtomically(dir / kRolesFile, roles.dump(2) + "\n");
  }
}

}  // namespace fvm::artefacts
