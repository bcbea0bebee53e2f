#pragma once
// A height map on a regular grid, as focus-variation instruments export it: z in mm, NaN where invalid. Heights are
// held as double so that a file's float64 heights (X3P D, and L with its increment) survive read, fit, correct and
// write unrounded; float32 and int16 heights convert to double exactly.

#include <cstddef>
#include <string>
#include <vector>

namespace fvm::imaging {

struct HeightMap {
  int size_x = 0;
  int size_y = 0;
  double dx_mm = 0.0;
  double dy_mm = 0.0;
  std::vector<double> z_mm;  // row-major, size_x * size_y; NaN marks an invalid point
  // Where the grid sits: point (ix, iy) is at x0_mm + ix * dx_mm, y0_mm + iy * dy_mm. Readers keep the file's
  // offsets so that tiles of one measurement stay in one frame.
  double x0_mm = 0.0;
  double y0_mm = 0.0;
  std::string source{};  // what the reader found about the origin (format, instrument, date); may be empty
  // The instrument's intensity (grey-level) image on the same grid, row-major, when the file holds one; empty
  // otherwise. Its unit is the instrument's (counts, 8-bit grey): for looking at, never for measuring.
  std::vector<float> intensity{};
  // What the reader found unusual about the file and read anyway, one sentence each (fvm info prints them).
  std::vector<std::string> notes{};

  double& at(int ix, int iy) { return z_mm[static_cast<size_t>(iy) * static_cast<size_t>(size_x) + static_cast<size_t>(ix)]; }
  double at(int ix, int iy) const { return z_mm[static_cast<size_t>(iy) * static_cast<size_t>(size_x) + static_cast<size_t>(ix)]; }
};

struct HeightMapStats {
  std::size_t valid_points = 0;
  double z_min_mm = 0.0;  // over valid points; 0 when there are none
  double z_max_mm = 0.0;
  double sq_mm = 0.0;  // Sq (ISO 25178-2): the RMS height about the mean of the valid points, no form removed
};

HeightMapStats ComputeStats(const HeightMap& map);

}  // namespace fvm::imaging
