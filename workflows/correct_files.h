#pragma once
// `fvm correct` as one job on files: the calibration file says which model it holds (a stage model of
// `fvm calibrate`, a machine model of `fvm verify`), the input what it is (a centre export, a list of nominal
// points, a scan: cloud or height map, or a tile layout); the job reads it, corrects it, writes the output and
// returns what the command prints and its --json document.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "imaging/io/surface_file.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct CorrectOptions {
  std::string calibration;                 // --calibration: the model file
  std::string input;                       // IN: centres, nominal points or a scan (not with a layout)
  std::string output;                      // -o: a file of the input's family; with a layout, a directory
  std::string frame = "stage";             // stage | first-tile
  std::string stitched_frame = "rotated";  // with the first-tile frame: rotated | translated
  std::string layout;                      // scans: tile layout file,row,col,x,y: one rigid shift per tile
  std::optional<Eigen::Vector3d> origin_mm;  // scans: the stage position of the file's coordinate origin
  double resample_mm = 0.0;                // scans: > 0, a height map on a regular grid of this pixel again
  bool extrapolate = false;                // scans: correct points outside the calibrated travel too
  imaging::SurfaceReadOptions read;        // scans: what images do not say about their pixels and heights
  int threads = 0;                         // 0: all cores
  std::string version;                     // the program's version, in the header of a corrected export

  // Throws InputError naming the option as the command line spells it (--frame, --resample, IN, ...).
  void Check() const;
};

struct CorrectedFiles {
  Summary summary;  // its JSON without the paths of the user's files; its text names them
  // The keys of those paths in the --json document ("input", "output", "layout"), for the command line to add.
  std::vector<std::pair<std::string, std::string>> paths;
};

// Throws InputError naming the file (and line, point or tile) for bad input; leaves no half-written output.
CorrectedFiles CorrectFiles(const CorrectOptions& options);

}  // namespace fvm::workflows
