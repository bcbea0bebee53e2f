#pragma once
// Alicona AL3D, the native export of Alicona InfiniteFocus instruments (layout as documented by the Gwyddion
// project's reader): the magic "AliconaImaging\0\r\n", fixed-size tags (20-byte key, 30-byte value, CRLF) of
// which "Version" and "TagCount" come first, a 256-byte comment, then images at the offsets the tags give.
// The depth image is float32 metres, little-endian, each row padded to a multiple of 8 bytes; pixels equal to
// InvalidPixelValue (or NaN) are invalid. Textures and the icon are skipped. AL3D carries no x/y origin.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file for anything wrong with it.
HeightMap ReadAl3d(const std::filesystem::path& path);
// The same from the file's bytes; `name` is what errors call the file.
HeightMap ParseAl3d(const std::string& bytes, const std::string& name);

// A minimal AL3D (depth image only, no texture or icon), for tests and interchange with tools that read
// AL3D. The origin (x0_mm, y0_mm) is not kept. Written atomically.
void WriteAl3d(const std::filesystem::path& path, const HeightMap& map);
std::string BuildAl3d(const HeightMap& map);

}  // namespace fvm::imaging
