// fvm simulate scan -o DIR: stitched calibration scans of a textured part on a stage with known errors (issue 21),
// with the layouts fvm calibrate --scan reads, the truth, and validation positions to judge the result by.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "artefacts/io/centre_export.h"
#include "artefacts/simulation/fvm_batch_simulation.h"
#include "artefacts/simulation/scan_simulation.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "imaging/io/tile_layout.h"
#include "stage/fvm_stage_models.h"
#include "stage/io/calibration_file.h"

namespace fvm::cli {
namespace {

constexpr double kDefaultPeriodicUm = 0.3;

struct SimulateScanArgs {
  std::string output;
  std::string truth_file;
  unsigned seed = 1;
  std::string lens = "5x";
  int tile_px = 1024;
  std::string overlap = "25";
  double length_mm = 150.0;
  std::string heights = "-50";
  std::string texture = "ground";
  std::string tiles = "grey";
  double periodic_um = -1.0;  // < 0: the truth file's, else kDefaultPeriodicUm
  double period_mm = 25.0;
  int validation = 200;
  double distortion_px = 0.0;  // radial field distortion k1 (px at the middle of each tile edge)
};

// A truth.json of `fvm simulate fvm-batch` (model + parameters) or a calibration file (fvm calibrate -o).
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
      throw InputError(path + ": parameter '" + name + "' is not a coefficient of model " + j["model"].get<std::string>() +
                       " with a numeric value");
    }
    truth.values[static_cast<size_t>(slot)] = p["value"].get<double>();
  }
  return truth;
}

void Run(const SimulateScanArgs& args) {
  std::string truth_model = "27";
  const auto load = [&] {
    if (!args.truth_file.empty()) return ReadStageTruth(args.truth_file, &truth_model);
    artefacts::FvmBatchOptions batch;  // the stage `fvm simulate fvm-batch --seed N` calibrates
    batch.seed = args.seed;
    const artefacts::FvmBatchTruth t = artefacts::SimulateFvmBatch(batch).truth;
    return artefacts::StageTruth{t.layout, t.values};
  };
  artefacts::StageTruth truth = load();
  if (args.periodic_um >= 0.0 || args.truth_file.empty()) {  // else the truth file's own: both simulators see one stage
    truth.periodic_um = args.periodic_um >= 0.0 ? args.periodic_um : kDefaultPeriodicUm;
    truth.period_mm = args.period_mm;
  }
  const imaging::Lens& lens = imaging::FindLens(args.lens);
  imaging::TilePlanOptions plan_options;
  plan_options.fov_mm = lens.fov_mm;
  plan_options.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  imaging::CalibrationScanOptions scan;
  const stage::Travel& tx = truth.layout.travel()[0];
  const stage::Travel& ty = truth.layout.travel()[1];
  scan.travel_min_mm = {tx.min, ty.min};
  scan.travel_max_mm = {tx.max, ty.max};
  scan.length_mm = args.length_mm;
  scan.heights_mm = ParseNumberList(args.heights, "--heights", "-50,-40");
  const std::vector<imaging::ScanPath> paths = imaging::PlanCalibrationScans(scan, plan_options);

  artefacts::ScanSimulationOptions options;
  options.tile_px = args.tile_px;
  options.pixel_mm = lens.fov_mm / args.tile_px;
  options.seed = args.seed;
  options.heights = args.tiles == "heights";
  try {
    options.camera = artefacts::ScanTexture(args.texture);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("--texture: ") + e.what());
  }
  if (args.distortion_px != 0.0) {
    options.distortion.width_px = options.distortion.height_px = args.tile_px;
    options.distortion.order = 3;
    const std::vector<std::string>& terms = imaging::FieldDistortionTermNames(3);
    options.distortion.coefficients = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(terms.size()));
    options.distortion.coefficients(std::find(terms.begin(), terms.end(), "k1") - terms.begin()) = args.distortion_px;
  }
  const std::filesystem::path dir(args.output);
  std::filesystem::create_directories(dir);
  int tiles = 0;
  for (const auto& p : paths) tiles += static_cast<int>(p.tiles.size());
  Progress progress("rendering and writing tiles", tiles, ShowProgress());
  for (const imaging::ScanPath& path : paths) {
    const std::vector<artefacts::SimulatedScan> rendered = artefacts::SimulateScans(truth, {path}, options);
    const artefacts::SimulatedScan& s = rendered.front();
    std::filesystem::create_directories(dir / path.name);
    std::vector<imaging::TileLayoutEntry> entries;
    for (size_t k = 0; k < path.tiles.size(); ++k) {
      const std::string file = fmt::format("{}/tile_{:03d}.tif", path.name, k);
      imaging::WriteTileImage(dir / file, s.images[k], options.heights ? imaging::TilePixelType::kFloat : imaging::TilePixelType::kUint16);
      imaging::TileLayoutEntry e;
      e.file = file;
      e.row = path.tiles[k].row;
      e.col = path.tiles[k].col;
      e.stage_mm = s.encoder_mm[k].head<2>();
      e.stage_z_mm = s.encoder_mm[k].z();
      entries.push_back(e);
      progress.Advance();
    }
    WriteFileAtomically(dir / (path.name + ".csv"), imaging::FormatTileLayout(entries));
  }
  progress.Finish();

  // Validation positions over the box the paths cover, at each height: where the stage says (free) and where it
  // really puts the optical axis (true). fvm correct of the free file against the true one judges a calibration.
  Eigen::Vector2d lo = paths.front().tiles.front().centre_mm, hi = lo;
  for (const auto& p : paths) {
    for (const auto& t : p.tiles) lo = lo.cwiseMin(t.centre_mm), hi = hi.cwiseMax(t.centre_mm);
  }
  std::mt19937_64 random(args.seed ^ 0x5ca7u);
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y());
  artefacts::CentreExport free, real;
  free.comments = {" validation positions: stage coordinates (encoder readings), mm"};
  real.comments = {" validation positions: where the stage really puts the optical axis (truth, part frame), mm"};
  for (int i = 0; i < args.validation; ++i) {
    const Eigen::Vector3d q(ux(random), uy(random), scan.heights_mm[static_cast<size_t>(i) % scan.heights_mm.size()]);
    artefacts::CentreRecord record;
    record.id = i + 1;
    record.position = q;
    free.centres.push_back(record);
    record.position = truth.Forward(q);
    real.centres.push_back(record);
  }
  artefacts::WriteCentreExport(dir / "validation.free.csv", free);
  artefacts::WriteCentreExport(dir / "validation.true.csv", real);

  nlohmann::json j;
  j["what"] = "stage the scans were simulated on (fvm simulate scan): the model's part and a periodic part it cannot take";
  j["model"] = truth_model;
  for (int i = 0; i < truth.layout.NumFree(); ++i) {
    j["parameters"].push_back({{"name", truth.layout.FreeNames()[static_cast<size_t>(i)]}, {"value", truth.values[static_cast<size_t>(i)]}});
  }
  j["periodic_um"] = truth.periodic_um;
  j["period_mm"] = truth.period_mm;
  j["pixel_mm"] = options.pixel_mm;
  j["lens"] = lens.name;
  j["tile_px"] = args.tile_px;
  j["texture"] = args.texture;
  j["tiles"] = args.tiles;
  j["seed"] = args.seed;
  j["distortion"] = {{"model", "radial k1: d = k1 (x, y) r^2, x, y about the tile centre in half tile widths"},
                     {"k1_px", args.distortion_px}};
  for (const auto& p : paths) j["scans"].push_back({{"name", p.name}, {"tiles", p.tiles.size()}, {"z_mm", p.z_mm}});
  WriteFileAtomically(dir / "truth.json", j.dump(2) + "\n");

  std::string layouts;
  for (const auto& p : paths) layouts += fmt::format(" --scan {}", (dir / (p.name + ".csv")).string());
  fmt::print("simulated {} scans ({} tiles of {} px, {} texture, pixel {:.6g} mm) into {}\n", paths.size(), tiles,
             args.tile_px, args.texture, options.pixel_mm, args.output);
  fmt::print("calibrate with:\n  fvm calibrate{} --pixel-mm {:.9g} --model 27 -o stage.json\n", layouts, options.pixel_mm);
}

}  // namespace

void RegisterSimulateScan(CLI::App* simulate) {
  auto args = std::make_shared<SimulateScanArgs>();
  CLI::App* sub = simulate->add_subcommand(
      "scan", "stitched calibration scans (row, column, diagonal) of a textured part on a stage with known errors: "
              "tiles rendered where the stage really puts every pixel, layouts with encoder readings, truth.json, "
              "validation positions");
  AddDetails(sub,
      "Plans a row along X, a column along Y and a diagonal through the travel (fvm tiles plan --calibration-scan) "
      "and renders every tile where the stage really puts each pixel: at F(e) + C(e) d for pixel offset d from the "
      "optical axis, so the tiles turn with the guideways. The part is one texture for all paths; 16-bit counts "
      "with shot and read noise, or height maps. Writes DIR/<path>.csv (file,row,col,x,y,z: encoder readings of the "
      "tile centres, mm), DIR/<path>/tile_NNN.tif, DIR/truth.json (the stage, pixel size, texture) and "
      "DIR/validation.free.csv / validation.true.csv (positions as the encoders read them, and where the stage "
      "really puts the optical axis).");
  sub->add_option("-o,--output", args->output, "directory to write")->required();
  sub->add_option("--calibration-truth", args->truth_file,
                  "the stage: a truth.json of fvm simulate fvm-batch, or a calibration file; default: the stage of "
                  "fvm simulate fvm-batch --seed N");
  sub->add_option("--seed", args->seed, "random seed: the stage (without --calibration-truth), texture and noise")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--lens", args->lens, "lens (field of view): 2.5x, 5x, 10x, ...")->capture_default_str();
  sub->add_option("--tile-px", args->tile_px, "square tiles of this many pixels")->check(Count(16, 8192))->capture_default_str();
  sub->add_option("--overlap", args->overlap, "overlap of consecutive tiles, percent or fraction")->check(OverlapCheck("--overlap"))->capture_default_str();
  sub->add_option("--length-mm", args->length_mm, "length of each path")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--heights", args->heights, "encoder z of each set of paths (mm), e.g. -50,-40 for a second height")
      ->check(NumbersCheck(0, "--heights", "-50,-40"))
      ->capture_default_str();
  sub->add_option("--texture", args->texture, "ground (fills the field), milled (a lay), blobs (sparse spots)")
      ->check(CLI::IsMember({"ground", "milled", "blobs"}))
      ->capture_default_str();
  sub->add_option("--tiles", args->tiles,
                  "grey: 16-bit images; heights: float TIFF height maps (mm, the part seen from each tile's focal "
                  "plane), whose overlaps give the stage's z steps too")
      ->check(CLI::IsMember({"grey", "heights"}))
      ->capture_default_str();
  sub->add_option("--periodic-um", args->periodic_um,
                  "a lead screw's cyclic error along X and Y the model cannot take (um); default: the truth file's, "
                  "else 0.3")
      ->check(Within(0.0, 1e3, "um"));
  sub->add_option("--period-mm", args->period_mm, "its period")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--distortion", args->distortion_px,
                  "radial field distortion of the objective, the same in every tile: px at the middle of each tile "
                  "edge (k1; barrel > 0, pincushion < 0); the truth is the stage's alone")
      ->check(Within(-50.0, 50.0, "px"));
  sub->add_option("--validation", args->validation, "validation positions to write")->check(Count(1, 1e6))->capture_default_str();
  sub->footer("Example:\n  fvm simulate scan -o scans --seed 1 --tile-px 256\n"
              "  fvm calibrate --scan scans/row.csv --scan scans/column.csv --scan scans/diagonal.csv --pixel-mm 0.01101563 "
              "--model 27 -o stage.json\n"
              "  fvm correct --calibration stage.json scans/validation.free.csv -o v.csv && fvm diff scans/validation.true.csv v.csv");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
