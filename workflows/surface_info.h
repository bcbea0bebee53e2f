#pragma once
// What a surface or point-cloud file holds (`fvm info`): format, grid, valid points, height range, so that a user
// can check an export before fitting calottes in it.

#include <optional>
#include <string>
#include <vector>

#include "imaging/io/surface_file.h"
#include "workflows/summary.h"

namespace fvm::workflows {

struct SurfaceInfo {
  std::string format;  // the reader's name for the file's format
  std::string kind;    // "height_map" or "point_cloud"
  std::string source;
  int size_x = 0, size_y = 0;
  std::optional<double> dx_mm, dy_mm, x0_mm, y0_mm;  // the grid, when there is one
  std::size_t points = 0, valid_points = 0;
  std::optional<double> x_min, x_max, y_min, y_max, z_min, z_max;  // over valid points
  std::optional<double> sq_mm;  // height maps: RMS height about the mean
  bool organised = false;
  bool intensity = false;          // the file holds an intensity image on the heights' grid
  std::vector<std::string> notes;  // what the reader found unusual and read anyway
};

// `name` (the file) names the surface where an organised cloud's grid is checked.
SurfaceInfo DescribeSurface(const imaging::Surface& surface, const std::string& name);

// The --json document {"size_x", "size_y", "dx_mm", "dy_mm", "valid_points", "z_min_mm", "z_max_mm", "format", ...,
// "notes"} (the command adds "file" before "format") and the text, headed by `name`.
Summary Summarize(const SurfaceInfo& info, const std::string& name);

}  // namespace fvm::workflows
