#pragma once
// NMS height images ("OM_MS_2.0", "Confocal Height Image"), the export of confocal microscopes read by surfalize
// (Schroeder 2024, nms.py); no published description exists and Gwyddion 2.62 does not read them. What fvm
// relies on, all checked against the file itself (little-endian):
//   int32 at 8 and 12: the lowest and highest count the heights use (0 and 65535);
//   float64 at 16 and 24: the lowest and highest height, micrometres;
//   int32 at 1352: the header's size (3468), where the data start; int32 at 1356: 2, the bytes per height;
//   uint32 at 1368 and 1372: columns and rows; float64 at 1376 and 1384: the x and y pixel, nanometres;
//   then columns x rows uint16 counts, row by row, and as many uint8 intensities.
// A height is the lowest height + (count - lowest count) / (highest count - lowest count) x the height range, so
// the header's two heights are the map's extremes: the file states its own check.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the field for anything wrong with it.
HeightMap ReadNms(const std::filesystem::path& path);
HeightMap ParseNms(const std::string& bytes, const std::string& name);

}  // namespace fvm::imaging
