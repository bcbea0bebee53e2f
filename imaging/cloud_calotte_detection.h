#pragma once
// Calottes in an unorganised point cloud, as instrument software exports a form measurement (MeasureSuite's 3D
// form measurement, Gwyddion, CloudCompare: PLY, PCD, XYZ). A microscope looking down sees one height per x, y,
// so its clouds are 2.5D: they are projected onto a grid of about four points per cell, where DetectCalottes
// (calotte_detection.h) finds the face and the dimples with the same screening and the same reasons as on a
// height map; then each sphere is fitted again, with the same estimator and options, to the cloud's own points
// of its dimple (below the face by the same depth threshold, inside the dimple's outline), so that the grid costs
// no accuracy: the centre's scatter is that of a fit to the raw points (its Cramer-Rao bound).
//
// A cloud that is not 2.5D (points above one another: the walls of a hole seen from the side, a whole part) is
// refused with what was found; organisation-free detection on normals and region growing (PCL) is not built.

#include <string>

#include "imaging/calotte_detection.h"
#include "imaging/point_cloud.h"

namespace fvm::imaging {

struct CloudCalotteDetection {
  CalotteDetection detection;  // fits on the cloud's own points; numbered, rejected and the face as on a map
  std::string method;          // how the calottes were found, for people ("grid projection (2.5D cloud), ...")
  double grid_mm = 0.0;        // the projection's cell size
};

// Throws InputError naming `name` for a cloud with too few valid points, or one that is not 2.5D.
CloudCalotteDetection DetectCalottesInCloud(const PointCloud& cloud, const CalotteDetectionOptions& options,
                                            const std::string& name);

}  // namespace fvm::imaging
