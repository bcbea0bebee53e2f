#pragma once
// The raw exports of a simulated batch: each placement's stitched and stitching-free measurement as a height map
// of the bar's face with its calottes rendered where that export places them (SimulatedFvmBatch::exact: the
// stitched frame of the first tile, or the stage's readings), then Gaussian height noise. What an instrument's
// X3P exports of the batch would hold, so that `fvm calibrate` can be run on surfaces (raw_export_batch.h).
//
// One surface per export spans the placement's calottes; only the face within margin_mm of each rim holds points
// (the rest is invalid, NaN), as a narrow bar across the stage and stitching-free tiles leave most of the span
// empty. The face rises along the bar as the calotte centres do and lies level across it (hemispheres in a flat bar),
// each sphere keeps its own height. The pixel is coarse by default (50 um: a bar turned by 45 degrees spans
// 2300 x 2300 points): a stitched mosaic of a 160 mm bar at the 5x lens' 2.75 um would span 3 billion.

#include <cstdint>

#include "artefacts/io/batch.h"
#include "imaging/height_map.h"

namespace fvm::artefacts {

struct RawExportSimulationOptions {
  double pixel_mm = 0.05;
  double noise_um = 2.0;     // height noise per pixel
  double margin_mm = 1.0;    // flat face beyond the outermost rims
  double radius_mm = 1.0;    // of the calottes (bar17)
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct RawExportPair {
  imaging::HeightMap stitched;
  imaging::HeightMap free;
};

// `placement` holds the exact centres of both exports (SimulatedFvmBatch::exact). Each export draws its noise
// from its own stream of `seed` and the placement's index.
RawExportPair RenderRawExports(const Placement& placement, std::size_t index, const RawExportSimulationOptions& options);

}  // namespace fvm::artefacts
