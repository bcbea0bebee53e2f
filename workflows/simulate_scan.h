#pragma once
// `fvm simulate scan -o DIR`: stitched calibration scans of a textured part on a stage with known errors (issue
// 21), with the layouts `fvm calibrate --scan` reads, the truth, and validation positions to judge the result by.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "artefacts/simulation/stage_truth.h"
#include "imaging/tile_plan.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// The options as `fvm simulate scan` spells them.
struct SimulateScanOptions {
  std::string calibration_truth;        // a truth.json of fvm simulate fvm-batch or a calibration file; empty: the
                                        // stage of fvm simulate fvm-batch --seed SEED
  unsigned seed = 1;
  std::string lens = "5x";
  int tile_px = 1024;
  std::string overlap = "25";           // percent or fraction
  double length_mm = 150.0;
  std::vector<double> heights_mm = {-50.0};  // encoder z of each set of paths
  std::string texture = "ground";       // ground, milled, blobs
  std::string tiles = "grey";           // grey (16-bit images) or heights (float height maps)
  double periodic_um = -1.0;            // < 0: the truth file's, else 0.3
  double period_mm = 25.0;
  int validation = 200;                 // validation positions
  double distortion_px = 0.0;           // radial field distortion k1 (px at the middle of each tile edge)

  // Throws InputError naming the option (--lens, --overlap, --texture, --tiles, --heights, ...).
  void Check() const;
};

struct SimulatedScans {
  std::filesystem::path dir;
  SimulateScanOptions options;
  std::string truth_model;              // "27", or the truth file's model
  artefacts::StageTruth truth;
  std::vector<imaging::ScanPath> paths;
  std::string lens;                     // the lens' name
  double pixel_mm = 0.0;
  int tiles = 0;
};

// A truth.json of `fvm simulate fvm-batch` (model + parameters) or a calibration file (fvm calibrate -o); `model`
// gets the model's name. Throws InputError naming the file.
artefacts::StageTruth ReadStageTruth(const std::string& path, std::string* model);

// Renders and writes the scans into `dir` (DIR/<path>.csv, DIR/<path>/tile_NNN.tif, DIR/validation.free.csv and
// validation.true.csv, DIR/truth.json). `on_start` hears the number of tiles, `on_tile` each tile written.
SimulatedScans SimulateScans(const SimulateScanOptions& options, const std::filesystem::path& dir,
                             const std::function<void(int)>& on_start = {}, const std::function<void()>& on_tile = {});

// The truth.json document as the JSON, and the lines the command prints (with the fvm calibrate line to run next).
Summary Summarize(const SimulatedScans& scans);

}  // namespace fvm::workflows
