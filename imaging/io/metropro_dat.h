#pragma once
// Zygo MetroPro DAT, the binary export of Zygo's white-light interferometers (NewView, Nexview, GPI, Verifire),
// as Zygo's MetroPro Reference Guide (OMP-0347, section 12, "Data file format") describes it and Gwyddion's reader
// (metropro.c, Necas and Klapetek 2005) reads it. Big-endian throughout:
//   the magic 0x881B036F, 0x881B0370 or 0x881B0371 (header formats 1, 2, 3; headers of 834, 834, 4096 bytes);
//   the intensity image: ac_width x ac_height uint16 per bucket (65535 and near it: no intensity);
//   the connected phase: cn_width x cn_height int32, row by row, >= 2147483640 where a point is invalid.
// A height is phase x intf_scale_factor x obliquity_factor x wavelength_in / R, with R 4096, 32768 or 131072 for
// phase_res 0, 1, 2, negated when the header's `sign` says the data are inverted; the pixel is lateral_res (m).

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the header field for anything wrong with it.
HeightMap ReadMetroProDat(const std::filesystem::path& path);
HeightMap ParseMetroProDat(const std::string& bytes, const std::string& name);

// Whether the first bytes are MetroPro's magic.
bool HasMetroProMagic(const std::string& head);

}  // namespace fvm::imaging
