#pragma once
// A height map again from an organised cloud whose points moved a little off their grid (a corrected height map:
// every point shifted by the stage error at its own position). Each cell of four valid neighbouring points is a
// small quadrilateral; every node of the new regular grid inside it takes the bilinear interpolation of the
// four heights at the node's position within the quadrilateral. Nodes no quadrilateral covers stay invalid (NaN):
// the holes and edges of the scan stay holes and edges.

#include <string>

#include "imaging/height_map.h"
#include "imaging/point_cloud.h"

namespace fvm::imaging {

// The new grid has `pixel_mm` spacing along x and y, nodes at whole multiples of it, and spans the cloud's valid
// points. Throws InputError (naming `name`) for an unorganised cloud, a non-positive pixel, no valid cell, or a
// grid of more than 2^31 nodes.
HeightMap ResampleOnGrid(const PointCloud& organised, double pixel_mm, const std::string& name);

}  // namespace fvm::imaging
