#pragma once
// Sensofar PLUx, the newer export of SensoSCAN / SensoVIEW (S neox, S lynx), as Gwyddion's reader (sensofarx.c,
// Necas 2017) reads it: a zip archive with index.xml, whose <GENERAL> gives IMAGE_SIZE_X and IMAGE_SIZE_Y (points)
// and FOV_X and FOV_Y (despite their names, the pixel sizes in micrometres), and whose <LAYER_n> elements name
// their height files in <FILENAME_Z>: IMAGE_SIZE_X x IMAGE_SIZE_Y float32 heights in micrometres, little-endian,
// row by row, NaN where a point is not measured. The first layer is read. Written from that description, with
// no instrument file to check against: tests/imaging/instrument_files_test.cc reads files laid out that way.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the element for anything wrong with it.
HeightMap ReadSensofarPlux(const std::filesystem::path& path);
HeightMap ParseSensofarPlux(std::string bytes, const std::string& name);

}  // namespace fvm::imaging
