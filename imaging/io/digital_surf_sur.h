#pragma once
// Digital Surf SUR, the surface format of MountainsMap (and the export of many instruments through it), as
// Digital Surf's file-format description in the MountainsMap documentation lays it out and Gwyddion (surffile.c)
// and surfalize (Schroeder 2024) read it. Little-endian ("PC format" 0):
//   a 512-byte header: the signature "DIGITAL SURF" (or "DSCOMPRESSED"), the number of objects, the studiable
//   type (2: a surface), a non-measured-points flag, bits per point (16 or 32), the declared minimum and maximum,
//   points per line and lines, the x, y, z spacings (float32) with their units ("mm", "um", "nm", ...), the z
//   offset (float32, in the z unit), the lengths of a comment and a private zone that follow the header;
//   the data: points per line x lines int16/int32 counts, row by row; "DSCOMPRESSED" stores them as zlib streams
//   after a uint32 count of (uint32 raw length, uint32 zipped length) directory pairs.
// A height is count x z spacing + z offset; with the non-measured flag, a count of (declared minimum - 2) marks
// a point not measured.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the header field for anything wrong with it.
HeightMap ReadDigitalSurfSur(const std::filesystem::path& path);
HeightMap ParseDigitalSurfSur(const std::string& bytes, const std::string& name);

}  // namespace fvm::imaging
