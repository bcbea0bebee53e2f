#pragma once
// A scan corrected with a stage model (`fvm correct` on a cloud or height map): every point by the model at its
// own stage coordinates, or, for data measured tile by tile, each tile by one rigid shift at its stage position.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "imaging/point_cloud.h"
#include "stage/calibration.h"
#include "stage/scan_correction.h"

namespace fvm::workflows {

struct ScanCorrectionJob {
  std::string calibration_name;           // the model's file, for messages
  stage::ScanCorrectionOptions options;   // frame, origin of the file's coordinates
  bool extrapolate = false;               // correct points outside the calibrated travel too
  int threads = 0;                        // 0: all cores
};

// Indices of the points (or tiles, then named by `tile_names`) outside the travel the model was identified on.
// Throws InputError naming up to five of them and the fix, unless the job extrapolates.
std::vector<std::size_t> CheckTravel(const ScanCorrectionJob& job, const stage::Calibration& calibration,
                                     const imaging::PointCloud& cloud, const std::string& name,
                                     const std::vector<std::string>& tile_names = {});

struct CorrectedCloud {
  // As the points were corrected: uncertainties elsewhere (a grid) come from it. It refers to the calibration,
  // which must outlive it.
  stage::ScanCorrector corrector;
  stage::ScanCorrectionSummary summary;
  std::vector<Eigen::Vector3d> u;        // standard uncertainties per point (mm) when asked
  std::vector<std::size_t> outside;      // points extrapolated
};

// The standard uncertainties (mm) the corrector gives each point; NaN for invalid points.
std::vector<Eigen::Vector3d> UncertaintiesAt(const stage::ScanCorrector& corrector,
                                             const std::vector<Eigen::Vector3d>& points);

// Corrects `cloud` in place. Throws InputError naming `name` when no point is valid or points lie outside the
// travel (unless the job extrapolates).
CorrectedCloud CorrectCloud(imaging::PointCloud& cloud, const stage::Calibration& calibration,
                            const ScanCorrectionJob& job, const std::string& name, bool with_uncertainty);

// One tile of a stitching-free scan: the whole tile moved by the stage model at its stage position.
struct TileShift {
  std::string file;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // stage, mm (z: the tile's median height)
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  double per_point_mm = 0.0;  // largest difference of the per-point correction from the shift at the tile's corners
};

struct TileCorrection {
  std::vector<TileShift> tiles;
  std::vector<std::size_t> outside;  // tiles extrapolated
  double largest_per_point_mm = 0.0;
  // The frame the shifts are in (first tile's, when the job asks for it).
  std::optional<Eigen::Vector3d> first_tile_mm;
};

struct TileInput {
  std::string file;                 // as the layout names it
  std::string path;                 // where it was read, for messages
  Eigen::Vector2d stage_xy_mm = Eigen::Vector2d::Zero();  // the layout's stage position of its centre
  const imaging::PointCloud* cloud = nullptr;             // its points, in the file's coordinates
};

// Throws InputError naming the tile's path for one without a valid point, and the layout `name` for tiles outside
// the travel (unless the job extrapolates).
TileCorrection CorrectTiles(const std::vector<TileInput>& tiles, const stage::Calibration& calibration,
                            const ScanCorrectionJob& job, const std::string& name);

}  // namespace fvm::workflows
