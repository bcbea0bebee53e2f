#pragma once
// GelSight TMD ("TrueMap data"), the height export of GelSight's elastomer-contact 3D scanners, as surfalize
// (Schroeder 2024, tmd.py) and x3ptools (Hofmann 2017, the R package's read_tmd) read it; Gwyddion 2.62 does not.
// Little-endian:
//   the signature "Binary TrueMap Data File v2.0\r\n\0" (32 bytes), then a NUL-terminated comment;
//   uint32 columns, uint32 rows, float32 length x, length y, offset x, offset y (millimetres);
//   columns x rows float32 heights (millimetres), row by row; NaN where a point is invalid.
// The pixel is the length over the number of columns (rows).

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the field for anything wrong with it.
HeightMap ReadGelSightTmd(const std::filesystem::path& path);
HeightMap ParseGelSightTmd(const std::string& bytes, const std::string& name);
// A TMD as GelSight writes it (v2.0, an empty comment), for tests and the fuzzers' seeds.
std::string BuildGelSightTmd(const HeightMap& map);

}  // namespace fvm::imaging
