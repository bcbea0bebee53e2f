#pragma once
// Height maps stored as images (TIFF, EXR, PNG, anything OpenImageIO reads): one grey channel of heights, an
// optional alpha channel whose zeros mark invalid points. Integer images hold counts (z = offset + scale *
// count); float images hold mm unless a z scale says otherwise.
//
// The pixel size and z scale come from the options when given, else from the file: the description fvm writes
// ("fvm height map; dx_mm=...; ..."), or a TIFF resolution in pixels per centimetre. Inch-based resolutions
// are ignored: image programs write 72 or 300 dpi into files that have nothing to do with a microscope.

#include <filesystem>
#include <optional>

#include "imaging/height_map.h"

namespace fvm::imaging {

struct HeightMapImageOptions {
  double dx_mm = 0.0;       // pixel size along x; 0: from the file
  double dy_mm = 0.0;       // along y; 0: same as dx (from the options or the file)
  double z_scale_mm = 0.0;  // mm per count (integer images) or per unit (float images); 0: from the file, else
                            // required for integer images and 1 for float images
  double z_offset_mm = 0.0;
  std::optional<double> invalid_value;  // the raw pixel value that marks "no measurement" (e.g. 0)

  // Throws InputError for negative or non-finite values.
  void Check() const;
};

// Throws InputError naming the file when it cannot be read, is a colour image, or its pixel size (or, for
// integer images, its z scale) is neither in the file nor in the options.
HeightMap ReadHeightMapImage(const std::filesystem::path& path, const HeightMapImageOptions& options = {});

// float32 heights in mm, NaN where invalid, with the grid in the description (and the pixel size as a TIFF
// resolution), so that ReadHeightMapImage restores the map exactly. TIFF or EXR by the path's extension.
// Written atomically.
void WriteHeightMapImage(const std::filesystem::path& path, const HeightMap& map);

}  // namespace fvm::imaging
