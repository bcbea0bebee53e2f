#pragma once
// Tile layouts of an FVM scan ([Pérez thesis] 5.7.2): the stitched grid that covers a region in the instrument's
// scan order, and the stitching-free subset of that grid that covers only given features (calottes).
//
// Frame and order. Stage coordinates in mm, +X right, +Y up. Tiles are squares of the lens' field of view F on a
// lattice of step s = F (1 - overlap). The grid is anchored where the instrument starts: the first tile's top-left
// corner is the region's (x0, y1) corner (lowest X, highest Y). Row 0 is the highest Y, column 0 the lowest X.
// Scan order is column by column from -X to +X, and inside a column from +Y to -Y, every column starting again at
// its top (a raster, not a serpentine): index = col * rows + row. This is the reading of [Pérez thesis] 5.7.2 ("first
// tile at lowest X and highest Y; tiles taken from +Y to -Y and -X to +X") with Y as the fast axis.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace fvm::imaging {

struct Lens {
  std::string name;  // "10x"
  double fov_mm = 0.0;
  double vertical_resolution_nm = 0.0;
};

// The Alicona G5 lenses of [Pérez thesis] Table 5.2. The 10x field is 1.62 mm as in that table; [Pérez 2019] says
// 1.4 mm, but only 1.62 mm reproduces the published 225 stitched tiles ([Pérez thesis] 5.7.2) (see tile_plan.cc).
const std::vector<Lens>& Lenses();
// Throws InputError naming the known lenses when `name` is none of them ("10x" and "10" both work).
const Lens& FindLens(std::string_view name);

struct Region {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  // mm, x0 < x1, y0 < y1
};

struct TilePlanOptions {
  double fov_mm = 1.62;  // square field of view of the lens
  double overlap = 0.2;  // fraction of the field shared by neighbouring tiles, in [0, 1)
  // Cost model, for comparing layouts; not published figures. 30 s per tile is a vertical scan of a few hundred
  // micrometres at 10x plus the stage move and settling; set it from your instrument's log.
  double seconds_per_tile = 30.0;
  // Per tile: the camera's pixels (assumed 1024 x 1024), each stored as a float height and an RGBA colour.
  int pixels_x = 1024;
  int pixels_y = 1024;
  int bytes_per_pixel = 8;
  void Check() const;  // throws InputError for a non-positive field, an overlap outside [0, 1), bad costs
};

struct Tile {
  int index = 0;  // position in the scan, 0 = first
  int row = 0;    // 0 = highest Y
  int col = 0;    // 0 = lowest X
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
};

struct TileGrid {
  int rows = 0, cols = 0;
  double fov_mm = 0.0, step_mm = 0.0;
  Eigen::Vector2d top_left_mm = Eigen::Vector2d::Zero();  // (x0, y1) of the region
  std::vector<Tile> tiles;                                 // scan order, rows * cols of them

  const Tile& At(int row, int col) const { return tiles[static_cast<size_t>(col * rows + row)]; }
};

// The fewest tiles per axis whose union covers the region: n = 1 + ceil((L - F) / s), 1 when L <= F.
// Throws InputError for an empty or inverted region.
TileGrid PlanStitchedGrid(const Region& region, const TilePlanOptions& options);

// Something that must be seen whole by the stitching-free scan: a calotte centre and its radius (mm).
struct Feature {
  int id = 0;
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
  double radius_mm = 0.0;
};

struct FeatureCover {
  int feature_id = 0;
  std::vector<int> tiles;  // grid indices (scan order) whose union contains the feature's bounding square
};

struct StitchingFreePlan {
  std::vector<Tile> tiles;  // a subset of the grid, scan order
  std::vector<FeatureCover> covers;
};

// The grid tiles a stitching-free scan needs so that every feature lies wholly inside the union of its tiles.
// A feature fits in one tile when the lattice allows, else in the fewest neighbouring ones (2 or 4 for features
// narrower than the step). Among equally small choices it takes tiles already chosen for earlier features, so
// the set is minimal for features farther apart than a tile (calotte grids) and greedy otherwise.
// Throws InputError naming the feature when it is not inside the grid.
StitchingFreePlan PlanStitchingFree(const TileGrid& grid, const std::vector<Feature>& features);

// An overlap as users write it: a fraction (0.2) or a percentage (20, 20%); values of 1 and above are percent.
// Throws InputError naming `what` (e.g. "--overlap") for text that is none of these, and for 0 or >= 100 %.
double ParseOverlap(std::string_view text, std::string_view what);

// Calibration scans (fvm tiles plan --calibration-scan, fvm calibrate --scan): straight paths of tiles over the
// travel, each overlapping the one before it, measured stitched. Their registrations carry the stage error at every
// tile. The row runs along X and the column along Y through the travel's centre, the diagonal from its upper left
// to its lower right, each `length_mm` long, and again at every further height. A diagonal's tiles step by
// fov (1 - overlap) along both axes: neighbours share an overlap^2 corner of the field.
struct CalibrationScanOptions {
  Eigen::Vector2d travel_min_mm{-200.0, -200.0}, travel_max_mm{0.0, 0.0};
  double length_mm = 150.0;
  std::vector<double> heights_mm{-50.0};  // the encoder z of each set of paths
  void Check() const;                     // throws InputError for a path longer than the travel, no heights
};
struct ScanPath {
  std::string name;                       // "row", "column", "diagonal"; "-z2" ... for further heights
  std::vector<Tile> tiles;                // scan order; row/col: 0 k (row), k 0 (column), k k (diagonal)
  double z_mm = 0.0;
};
std::vector<ScanPath> PlanCalibrationScans(const CalibrationScanOptions& scan, const TilePlanOptions& options);

struct ScanCost {
  int tiles = 0;
  double seconds = 0.0;
  double bytes = 0.0;
};
ScanCost EstimateScan(int tiles, const TilePlanOptions& options);

}  // namespace fvm::imaging
