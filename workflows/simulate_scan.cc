#include "workflows/simulate_scan.h"

#include <fmt/core.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "imaging/io/tile_layout.h"
#include "stage/fvm_stage_models.h"
#include "stage/io/calibration_file.h"

namespace fvm::workflows {
namespace {

constexpr double kDefaultPeriodicUm = 0.3;

// The stage: the truth file's, or the one `fvm simulate fvm-batch --seed N` calibrates; its periodic part the
// option's when given (else the file's, so that both simulators see one stage).
artefacts::StageTruth LoadScanTruth(const SimulateScanOptions& o, std::string* model) {
  *model = "27";
  const auto load = [&] {
    if (!o.calibration_truth.empty()) return ReadStageTruth(o.calibration_truth, model);
    artefacts::FvmBatchOptions batch;
    batch.seed = o.seed;
    const artefacts::FvmBatchTruth t = artefacts::SimulateFvmBatch(batch).truth;
    return artefacts::StageTruth{t.layout, t.values};
  };
  artefacts::StageTruth truth = load();
  if (o.periodic_um >= 0.0 || o.calibration_truth.empty()) {
    truth.periodic_um = o.periodic_um >= 0.0 ? o.periodic_um : kDefaultPeriodicUm;
    truth.period_mm = o.period_mm;
  }
  return truth;
}

std::vector<imaging::ScanPath> PlanScans(const SimulateScanOptions& o, const artefacts::StageTruth& truth,
                                         const imaging::Lens& lens) {
  imaging::TilePlanOptions plan;
  plan.fov_mm = lens.fov_mm;
  plan.overlap = imaging::ParseOverlap(o.overlap, "--overlap");
  imaging::CalibrationScanOptions scan;
  const stage::Travel& tx = truth.layout.travel()[0];
  const stage::Travel& ty = truth.layout.travel()[1];
  scan.travel_min_mm = {tx.min, ty.min};
  scan.travel_max_mm = {tx.max, ty.max};
  scan.length_mm = o.length_mm;
  scan.heights_mm = o.heights_mm;
  return imaging::PlanCalibrationScans(scan, plan);
}

artefacts::ScanSimulationOptions RenderOptions(const SimulateScanOptions& o, const imaging::Lens& lens) {
  artefacts::ScanSimulationOptions r;
  r.tile_px = o.tile_px;
  r.pixel_mm = lens.fov_mm / o.tile_px;
  r.seed = o.seed;
  r.heights = o.tiles == "heights";
  try {
    r.camera = artefacts::ScanTexture(o.texture);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("--texture: ") + e.what());
  }
  if (o.distortion_px != 0.0) {
    r.distortion.width_px = r.distortion.height_px = o.tile_px;
    r.distortion.order = 3;
    const std::vector<std::string>& terms = imaging::FieldDistortionTermNames(3);
    r.distortion.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(terms.size()));
    r.distortion.coefficients(std::find(terms.begin(), terms.end(), "k1") - terms.begin()) = o.distortion_px;
  }
  return r;
}

void WriteScanTiles(const SimulatedScans& s, const artefacts::ScanSimulationOptions& render,
                    const std::function<void()>& on_tile) {
  for (const imaging::ScanPath& path : s.paths) {
    const std::vector<artefacts::SimulatedScan> rendered = artefacts::SimulateScans(s.truth, {path}, render);
    const artefacts::SimulatedScan& scan = rendered.front();
    std::filesystem::create_directories(s.dir / path.name);
    std::vector<imaging::TileLayoutEntry> entries;
    for (size_t k = 0; k < path.tiles.size(); ++k) {
      const std::string file = fmt::format("{}/tile_{:03d}.tif", path.name, k);
      imaging::WriteTileImage(s.dir / file, scan.images[k],
                              render.heights ? imaging::TilePixelType::kFloat : imaging::TilePixelType::kUint16);
      imaging::TileLayoutEntry e;
      e.file = file;
      e.row = path.tiles[k].row;
      e.col = path.tiles[k].col;
      e.stage_mm = scan.encoder_mm[k].head<2>();
      e.stage_z_mm = scan.encoder_mm[k].z();
      entries.push_back(e);
      if (on_tile) on_tile();
    }
    WriteFileAtomically(s.dir / (path.name + ".csv"), imaging::FormatTileLayout(entries));
  }
}

// Validation positions over the box the paths cover, at each height: where the stage says (free) and where it
// really puts the optical axis (true). fvm correct of the free file against the true one judges a calibration.
void WriteValidation(const SimulatedScans& s) {
  Eigen::Vector2d lo = s.paths.front().tiles.front().centre_mm, hi = lo;
  for (const auto& p : s.paths) {
    for (const auto& t : p.tiles) lo = lo.cwiseMin(t.centre_mm), hi = hi.cwiseMax(t.centre_mm);
  }
  std::mt19937_64 random(s.options.seed ^ 0x5ca7u);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y());
  artefacts::CentreExport free, real;
  free.comments = {" validation positions: stage coordinates (encoder readings), mm"};
  real.comments = {" validation positions: where the stage really puts the optical axis (truth, part frame), mm"};
  const std::vector<double>& heights = s.options.heights_mm;
  for (int i = 0; i < s.options.validation; ++i) {
    const Eigen::Vector3d q(ux(random), uy(random), heights[static_cast<size_t>(i) % heights.size()]);
    artefacts::CentreRecord record;
    record.id = i + 1;
    record.position = q;
    free.centres.push_back(record);
    record.position = s.truth.Forward(q);
    real.centres.push_back(record);
  }
  artefacts::WriteCentreExport(s.dir / "validation.free.csv", free);
  artefacts::WriteCentreExport(s.dir / "validation.true.csv", real);
}

// truth.json (sorted keys, as always written).
nlohmann::json ScanTruthDocument(const SimulatedScans& s) {
  nlohmann::json j;
  j["what"] = "stage the scans were simulated on (fvm simulate scan): the model's part and a periodic part it cannot take";
  j["model"] = s.truth_model;
  for (int i = 0; i < s.truth.layout.NumFree(); ++i) {
    j["parameters"].push_back({{"name", s.truth.layout.FreeNames()[static_cast<size_t>(i)]},
                               {"value", s.truth.values[static_cast<size_t>(i)]}});
  }
  j["periodic_um"] = s.truth.periodic_um;
  j["period_mm"] = s.truth.period_mm;
  j["pixel_mm"] = s.pixel_mm;
  j["lens"] = s.lens;
  j["tile_px"] = s.options.tile_px;
  j["texture"] = s.options.texture;
  j["tiles"] = s.options.tiles;
  j["seed"] = s.options.seed;
  j["distortion"] = {{"model", "radial k1: d = k1 (x, y) r^2, x, y about the tile centre in half tile widths"},
                     {"k1_px", s.options.distortion_px}};
  for (const auto& p : s.paths) j["scans"].push_back({{"name", p.name}, {"tiles", p.tiles.size()}, {"z_mm", p.z_mm}});
  return j;
}

}  // namespace

artefacts::StageTruth ReadStageTruth(const std::string& path, std::string* model) {
  const nlohmann::json j = ReadJsonFile(path, "give a truth.json of fvm simulate fvm-batch or a calibration file");
  if (j.contains("format")) {
    const stage::Calibration c = stage::ReadCalibration(path);
    *model = c.model;
    return artefacts::StageTruth{c.layout, c.values};
  }
  if (!j.contains("model") || !j["model"].is_string() || !j.contains("parameters") || !j["parameters"].is_array()) {
    throw InputError(path + ": neither a calibration file nor a truth.json of fvm simulate fvm-batch (model, parameters)");
  }
  *model = j["model"].get<std::string>();
  const auto layout = [&] {
    try {
      // "27", or "terms:<spec>" for a truth of one's own form (ModelName)
      return model->starts_with("terms:") ? stage::ComposeLayout(model->substr(6)) : stage::FvmModelLayout(*model);
    } catch (const std::invalid_argument& e) {
      throw InputError(path + ": model: " + e.what());
    }
  };
  artefacts::StageTruth truth{layout(), {}, j.value("periodic_um", 0.0), j.value("period_mm", 25.0)};
  truth.values.assign(static_cast<size_t>(truth.layout.NumFree()), 0.0);
  for (const auto& p : j["parameters"]) {
    const std::string name = p.value("name", "");
    const int slot = truth.layout.FreeIndexOf(name);
    if (slot < 0 || !p.contains("value") || !p["value"].is_number()) {
      throw InputError(path + ": parameter '" + name + "' is not a coefficient of model " + *model +
                       " with a numeric value");
    }
    truth.values[static_cast<size_t>(slot)] = p["value"].get<double>();
  }
  return truth;
}

void SimulateScanOptions::Check() const {
  imaging::ParseOverlap(overlap, "--overlap");
  if (tile_px < 16 || tile_px > 8192) throw InputError(fmt::format("--tile-px {}: use 16 to 8192", tile_px));
  if (heights_mm.empty()) throw InputError("--heights: give at least one encoder z, e.g. -50,-40");
  if (tiles != "grey" && tiles != "heights") throw InputError("--tiles '" + tiles + "': use grey or heights");
  if (validation < 1) throw InputError(fmt::format("--validation {}: write at least one position", validation));
}

SimulatedScans SimulateScans(const SimulateScanOptions& options, const std::filesystem::path& dir,
                             const std::function<void(int)>& on_start, const std::function<void()>& on_tile) {
  options.Check();
  std::string model;
  artefacts::StageTruth truth = LoadScanTruth(options, &model);
  SimulatedScans s{dir, options, model, std::move(truth), {}, "", 0.0, 0};
  const imaging::Lens& lens = imaging::FindLens(options.lens);
  s.lens = lens.name;
  s.paths = PlanScans(options, s.truth, lens);
  const artefacts::ScanSimulationOptions render = RenderOptions(options, lens);
  s.pixel_mm = render.pixel_mm;
  std::filesystem::create_directories(dir);
  for (const auto& p : s.paths) s.tiles += static_cast<int>(p.tiles.size());
  if (on_start) on_start(s.tiles);
  WriteScanTiles(s, render, on_tile);
  WriteValidation(s);
  WriteFileAtomically(dir / "truth.json", ScanTruthDocument(s).dump(2) + "\n");
  return s;
}

Summary Summarize(const SimulatedScans& s) {
  Summary summary;
  summary.json = nlohmann::ordered_json::parse(ScanTruthDocument(s).dump());  // the file's keys in its order
  std::string layouts;
  for (const auto& p : s.paths) layouts += fmt::format(" --scan {}", (s.dir / (p.name + ".csv")).string());
  summary.text = fmt::format("simulated {} scans ({} tiles of {} px, {} texture, pixel {:.6g} mm) into {}\n",
                             s.paths.size(), s.tiles, s.options.tile_px, s.options.texture, s.pixel_mm, s.dir.string());
  // Tiles through a field: the command that identifies it too (without it, the field's scale passes for stage error).
  summary.text += fmt::format("calibrate with:\n  fvm calibrate{} --pixel-mm {:.9g} --model 27{} -o stage.json\n", layouts,
                              s.pixel_mm, s.options.distortion_px != 0.0 ? " --distortion" : "");
  return summary;
}

}  // namespace fvm::workflows
