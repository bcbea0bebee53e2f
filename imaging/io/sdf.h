#pragma once
// ISO 25178-71 surface data files (SDF; the format of Stout et al. 1993 that the standard adopted), in both of
// its forms:
// - ASCII, "aISO-1.0": header lines "Key = value" up to a line "*" (NumPoints points per profile, NumProfiles
//   profiles, Xscale / Yscale / Zscale in metres per unit), then NumPoints x NumProfiles numbers separated by
//   white space, profile after profile, up to a "*"; a free-text trailer may follow.
// - binary, "bISO-1.0": an 81-byte little-endian header (version 8 bytes, ManufacID 10, CreateDate 12, ModDate 12,
//   NumPoints and NumProfiles uint16, Xscale, Yscale, Zscale, Zresolution float64, Compression, DataType and
//   CheckType one byte each), then the values, of DataType 0-7 (uint8, uint16, uint32, float32, int8, int16,
//   int32, float64, as Gwyddion numbers them), profile after profile.
// A height is value x Zscale; points along x are Xscale apart, profiles Yscale apart. SDF has no origin and no
// invalid-point marker (a NaN value is invalid). Compressed data (Compression != 0) is refused.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file for anything wrong with it.
HeightMap ReadSdf(const std::filesystem::path& path);
// The same from the file's bytes; `name` is what errors call the file.
HeightMap ParseSdf(const std::string& bytes, const std::string& name);

}  // namespace fvm::imaging
