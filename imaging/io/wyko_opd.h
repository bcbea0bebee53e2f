#pragma once
// Wyko OPD, the binary export of Veeco / Bruker Wyko white-light interferometers (NT1100, NT9100, ContourGT's
// Vision software), as Gwyddion's reader (opdfile.c, Necas 2008) reads it. Little-endian:
//   2 bytes, then a directory of 24-byte entries: a 16-byte name, int16 type, int32 length, uint16 attributes; the
//   first entry, "Directory", gives the directory's own length. The blocks follow the directory in the order of
//   its entries.
//   RAW_DATA (type 3, an array): uint16 columns, uint16 rows, uint16 bytes per value (2: int16, 4: float32), then
//   the values column by column, each column from the bottom row up. int16 32767 (float >= 1e38) is a point not
//   measured. A height is value x Wavelength (nm) / Mult.
//   Pixel_size (float32, mm) is the x spacing; Aspect (float32, 1 when absent) is y over x.
//   Image (type 3), when present, is the intensity image laid out as RAW_DATA.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the block for anything wrong with it.
HeightMap ReadWykoOpd(const std::filesystem::path& path);
HeightMap ParseWykoOpd(const std::string& bytes, const std::string& name);

// Whether the first bytes are an OPD directory.
bool HasWykoOpdDirectory(const std::string& head);

}  // namespace fvm::imaging
