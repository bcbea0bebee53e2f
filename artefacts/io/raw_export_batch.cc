#include "artefacts/io/raw_export_batch.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "artefacts/calotte_numbering_by_layout.h"
#include "core/input_error.h"
#include "imaging/calotte_numbering.h"
#include "imaging/io/surface_file.h"

namespace fvm::artefacts {
namespace {

constexpr std::string_view kStitched = ".stitched";
constexpr std::string_view kFree = ".free";

// "<name>.stitched" or "<name>.free" with a surface extension: the placement name and the export, else nullopt.
std::optional<std::pair<std::string, bool>> ExportOf(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  const std::vector<std::string>& known = RawExportExtensions();
  if (std::find(known.begin(), known.end(), ext) == known.end()) return std::nullopt;
  const std::string stem = file.stem().string();
  for (const auto& [suffix, stitched] : {std::pair{kStitched, true}, std::pair{kFree, false}}) {
    if (stem.size() > suffix.size() && stem.ends_with(suffix)) {
      return std::pair{stem.substr(0, stem.size() - suffix.size()), stitched};
    }
  }
  return std::nullopt;
}

struct ExportFiles {
  std::vector<std::filesystem::path> stitched, free;
};

std::map<std::string, ExportFiles> FindExports(const std::filesystem::path& dir) {
  std::map<std::string, ExportFiles> found;
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) return found;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    if (const auto which = ExportOf(entry.path())) {
      ExportFiles& files = found[which->first];
      (which->second ? files.stitched : files.free).push_back(entry.path());
    }
  }
  for (auto& [name, files] : found) {
    std::sort(files.stitched.begin(), files.stitched.end());
    std::sort(files.free.begin(), files.free.end());
  }
  return found;
}


// The calotte search and numbering of `fvm fit --artefact`, on one surface.
struct Numbered {
  imaging::CalotteDetection detection;
  imaging::LayoutMatch layout;
};

Numbered SearchAndNumber(const std::filesystem::path& file, const Artefact& artefact,
                         const imaging::LayoutMatchOptions& match, bool retry_turned) {
  imaging::Surface surface = imaging::ReadSurface(file);
  if (!surface.height_map) {
    throw InputError(fmt::format("{}: a point cloud; a raw batch holds height maps (X3P, AL3D, SDF, TIFF): fit a "
                                 "cloud with 'fvm fit FILE --artefact {} -o FILE.csv' and give the centre exports",
                                 file.string(), artefact.name));
  }
  if (surface.height_map->x0_mm == 0.0 && surface.height_map->y0_mm == 0.0) {
    // Stitching-free centres are stage readings: a map without its position would calibrate a stage shifted to 0.
    throw InputError(fmt::format("{}: the surface starts at (0, 0) mm, so it carries no stage position (AL3D and "
                                 "plain images do not); export X3P, whose axes hold the position, or fit the calottes "
                                 "with 'fvm fit' and give their stage coordinates as a centre export",
                                 file.string()));
  }
  const imaging::CalotteDetectionOptions options = CalotteSearchFor(artefact);
  Numbered out;
  try {
    out.detection = imaging::DetectCalottes(*surface.height_map, options);
    if (out.detection.calottes.empty()) {
      throw InputError(fmt::format("no calotte of {} found: no round depression {}-{} mm across below the face",
                                   artefact.name, options.min_diameter_mm, options.max_diameter_mm));
    }
    out.layout = NumberByLayout(out.detection, artefact, match, retry_turned);
  } catch (const InputError& e) {
    throw InputError(file.string() + ": " + e.what());
  }
  return out;
}

RawExportFit ToExport(const std::string& placement, const std::filesystem::path& file, bool stitched,
                      const Numbered& numbered, const std::string& artefact) {
  RawExportFit fit{placement, file, stitched, {}, numbered.detection.rejected.size()};
  fit.centres.source = file.string();
  fit.centres.comments.push_back(fmt::format("fvm calibrate: calottes of {} found in {} and numbered by its layout "
                                             "(turned {:.3f} deg); face noise {:.3f} um",
                                             artefact, file.filename().string(),
                                             numbered.layout.rotation_rad * 180 / M_PI,
                                             numbered.detection.face.sigma_mm * 1e3));
  AddFoundCentres(numbered.detection, fit.centres);
  return fit;
}

// The two numberings must name the same calottes, and the same calotte must sit at the same place of the
// placement's shape in both exports (a mirrored or shifted numbering moves calottes by whole spacings).
void CheckSameNumbering(const RawExportFit& stitched, const RawExportFit& free, const Artefact& artefact) {
  std::vector<int> only_stitched, only_free, common;
  for (const CentreRecord& c : stitched.centres.centres) {
    (free.centres.Find(c.id) ? common : only_stitched).push_back(c.id);
  }
  for (const CentreRecord& c : free.centres.centres) {
    if (!stitched.centres.Find(c.id)) only_free.push_back(c.id);
  }
  if (!only_stitched.empty() || !only_free.empty()) {
    std::string what;
    if (!only_stitched.empty()) {
      what += fmt::format("calotte {} found in {} but not in {}", fmt::join(only_stitched, ", "), stitched.file.string(),
                          free.file.string());
    }
    if (!only_free.empty()) {
      what += fmt::format("{}calotte {} found in {} but not in {}", what.empty() ? "" : "; ", fmt::join(only_free, ", "),
                          free.file.string(), stitched.file.string());
    }
    throw InputError(fmt::format("placement {}: the two exports do not number the same calottes: {}; measure the "
                                 "missing calottes again, or move the placement out of the batch",
                                 stitched.placement, what));
  }
  double spacing = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < artefact.calottes.size(); ++i) {
    for (size_t j = i + 1; j < artefact.calottes.size(); ++j) {
      spacing = std::min(spacing, (artefact.calottes[i].centre - artefact.calottes[j].centre).head<2>().norm());
    }
  }
  std::vector<int> astray;
  double worst = 0;
  for (int id : common) {
    const double apart = (stitched.centres.Find(id)->position - free.centres.Find(id)->position).head<2>().norm();
    if (apart > 0.25 * spacing) astray.push_back(id);
    worst = std::max(worst, apart);
  }
  if (!astray.empty()) {
    throw InputError(fmt::format(
        "placement {}: calotte {} numbered differently in {} and {}: up to {:.3f} mm apart, more than a quarter of "
        "the {:.3g} mm spacing (the stitched export lies at its first tile's stage reading, so one calotte lies "
        "within the stage error in both); check that both exports show the same placement and carry the stage "
        "position",
        stitched.placement, fmt::join(astray, ", "), stitched.file.string(), free.file.string(), worst, spacing));
  }
}

}  // namespace

const std::vector<std::string>& RawExportExtensions() {
  static const std::vector<std::string> extensions = {".x3p", ".al3d", ".sdf", ".tif",  ".tiff", ".plu",
                                                      ".dat", ".opd", ".sur",  ".nms", ".tmd"};
  return extensions;
}

void AddFoundCentres(const imaging::CalotteDetection& detection, CentreExport& out) {
  for (const auto& c : detection.calottes) {
    CentreRecord record;
    record.id = c.id;
    record.position = c.fit.centre_mm;
    record.radius_mm = c.fit.radius_mm;
    record.form_rms_mm = c.fit.rms_deviation_mm;
    record.converged = c.fit.converged;
    out.centres.push_back(record);
    // The column says 0; the comment says why, for the person who opens the file.
    if (!c.fit.converged) out.comments.push_back(fmt::format("calotte {}: sphere fit NOT converged ({})", c.id, c.fit.stop_reason));
  }
}

imaging::CalotteDetectionOptions CalotteSearchFor(const Artefact& artefact) {
  imaging::CalotteDetectionOptions options;
  double diameter = 0;
  for (const Calotte& c : artefact.calottes) diameter = std::max(diameter, 2 * c.radius_mm);
  options.min_diameter_mm = 0.3 * diameter;
  options.max_diameter_mm = 1.5 * diameter;
  return options;
}

bool HoldsRawExports(const std::filesystem::path& dir) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) return false;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".stitched.csv")) return false;
  }
  return !FindExports(dir).empty();
}

void WriteRawExportCentres(const std::filesystem::path& dir, const RawExportBatch& raw) {
  std::error_code error;
  if (std::filesystem::weakly_canonical(dir, error) == std::filesystem::weakly_canonical(raw.batch.dir, error)) {
    throw InputError(fmt::format("{}: the centre exports would go into the batch of surfaces itself (beside, and "
                                 "over, its batch.json); name another directory",
                                 dir.string()));
  }
  Batch roles = raw.batch;
  roles.placements.clear();  // WriteBatch then writes batch.json alone
  WriteBatch(dir, roles);
  for (const RawExportFit& fit : raw.fits) {
    WriteCentreExport(dir / (fit.placement + (fit.stitched ? ".stitched.csv" : ".free.csv")), fit.centres);
  }
}

RawExportBatch ReadRawExportBatch(const std::filesystem::path& dir, const RawExportBatchOptions& options) {
  const Artefact artefact = KnownArtefact(options.artefact);
  const std::map<std::string, ExportFiles> found = FindExports(dir);
  if (found.empty()) {
    throw InputError(fmt::format("{}: no raw exports; a raw batch holds <placement>.stitched.x3p and "
                                 "<placement>.free.x3p (or .al3d, .sdf, .tif)",
                                 dir.string()));
  }
  for (const auto& [name, files] : found) {
    for (const auto* list : {&files.stitched, &files.free}) {
      if (list->size() > 1) {
        throw InputError(fmt::format("{} and {}: two surfaces of one export; keep one of them in the batch",
                                     (*list)[0].string(), (*list)[1].string()));
      }
    }
    if (files.stitched.empty() || files.free.empty()) {
      const std::filesystem::path& has = files.stitched.empty() ? files.free[0] : files.stitched[0];
      throw InputError(fmt::format("{}: has no partner {}{}.*; measure the placement {} stitching too, or move the "
                                   "file out of the batch",
                                   has.string(), (dir / name).string(), files.stitched.empty() ? kStitched : kFree,
                                   files.stitched.empty() ? "with" : "without"));
    }
  }

  RawExportBatch out;
  out.batch.dir = dir;
  for (const auto& [name, files] : found) {  // std::map: sorted by name
    imaging::LayoutMatchOptions match;
    match.expected_rotation_rad = options.expected_rotation_rad;
    const Numbered stitched = SearchAndNumber(files.stitched[0], artefact, match, true);
    match.expected_rotation_rad = stitched.layout.rotation_rad;  // the free export follows its numbering
    const Numbered free = SearchAndNumber(files.free[0], artefact, match, false);
    RawExportFit stitched_fit = ToExport(name, files.stitched[0], true, stitched, artefact.name);
    RawExportFit free_fit = ToExport(name, files.free[0], false, free, artefact.name);
    CheckSameNumbering(stitched_fit, free_fit, artefact);
    out.batch.placements.push_back(PairCentreExports(name, stitched_fit.centres, free_fit.centres));
    out.fits.push_back(std::move(stitched_fit));
    out.fits.push_back(std::move(free_fit));
  }
  ApplyBatchRoles(dir, out.batch);
  return out;
}

}  // namespace fvm::artefacts
