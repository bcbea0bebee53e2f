#pragma once
// Finds calottes (spherical dimples, 0.5-2 mm across) in a height map and fits a sphere to each.
//
// 1. The face: a plane z = a + b x + c y through the map by least median of squares (seeded; survives a
//    dimple that covers almost half the map), refined by least squares with trimming; its robust residual
//    sigma is the map's noise.
// 2. Depressions: valid points more than min_depth below the face, 8-connected (a dropout does not split a
//    dimple; burrs and spikes above the face never join it). A component is a calotte when its extent fits
//    the diameter range, it is round and mostly filled; otherwise it is listed as rejected with the reason
//    (an artefact edge, a scratch, two calottes run together, a speck).
// 3. A sphere per calotte through the points of its dimple (imaging/sphere_fit.h), by default with the height
//    residual and trimming, in the map's coordinates: x0 + ix dx, y0 + iy dy, z.
// Calottes are listed row by row: top (largest y) to bottom, left to right. To number them as the artefact
// does, match them to a nominal layout (imaging/calotte_numbering.h).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "imaging/height_map.h"
#include "imaging/sphere_fit.h"

namespace fvm::imaging {

struct CalotteDetectionOptions {
  double min_diameter_mm = 0.3;  // extents outside [min, max] of a component are not a calotte
  double max_diameter_mm = 3.0;
  // Depth below the face that marks a point as part of a dimple; 0 picks 8 robust sigmas of the face's noise
  // (never below 0.5 um), so that no point of the face enters a fit.
  double min_depth_mm = 0.0;
  int min_points = 30;  // fewer points of a dimple: not worth a sphere
  SphereFitOptions fit = [] {
    SphereFitOptions o;
    o.residual = SphereResidual::kHeight;  // focus variation measures heights: noise is along z
    return o;
  }();
  std::uint64_t seed = 1;  // the face's least-median-of-squares draws
  void Check() const;      // throws std::invalid_argument
};

// z = a + b x + c y with its robust residual sigma, fitted to the face the calottes are cut into.
struct FacePlane {
  double a = 0.0, b = 0.0, c = 0.0;
  double sigma_mm = 0.0;
  std::size_t points = 0;  // face points that fitted it
  double Height(double x, double y) const { return a + b * x + c * y; }
};

struct DetectedCalotte {
  int id = 0;  // 1.. in listing order; the artefact's number after NumberCalottes
  SphereFit fit;
  Eigen::Vector2d extent_mm = Eigen::Vector2d::Zero();  // width and height of the dimple's bounding box
  double depth_mm = 0.0;                                // deepest point below the face
  bool at_border = false;                               // the dimple runs into the map's border: a partial cap
};

struct RejectedRegion {
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();  // of its bounding box
  Eigen::Vector2d extent_mm = Eigen::Vector2d::Zero();
  std::size_t points = 0;
  std::string reason;
};

struct CalotteDetection {
  FacePlane face;
  double min_depth_mm = 0.0;  // the threshold used
  std::vector<DetectedCalotte> calottes;
  std::vector<RejectedRegion> rejected;  // depressions of at least min_points that were not taken as calottes
};

// Throws InputError when the map holds no valid points or too few to find a face.
CalotteDetection DetectCalottes(const HeightMap& map, const CalotteDetectionOptions& options = {});

}  // namespace fvm::imaging
