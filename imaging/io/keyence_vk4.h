#pragma once
// Keyence VK4, the export of Keyence's VK-X laser confocal microscopes, as Gwyddion's keyence.c (Necas 2015) and
// surfalize (Schroeder 2024, vk4.py) read it. No instrument file was at hand: the reader follows those
// descriptions and is tested on files written the same way (tests/support/instrument_files.h). Little-endian:
//   "VK4_", 4 bytes of DLL version, 4 zero bytes (file type: a single measurement);
//   an offset table of 18 uint32 from byte 12: measurement conditions, colour peak, colour + light, light[3],
//     height[3], four thumbnails, assembly, line measurement, line thickness, strings, reserved (0: absent);
//   the measurement conditions (uint32 size >= 304, then uint32 fields): x and y length per pixel and z length
//     per digit in picometres at bytes 168, 172 and 176 of the block;
//   each image: uint32 width, height, bit depth (8, 16, 32), compression (0), byte size, palette min and max,
//     a 768-byte palette, then width x height unsigned counts row by row;
//   the strings: a uint32 count and that many UTF-16 units, the title then the lens name.
// Heights are height[0]'s counts times z length per digit; the light[0] image is the intensity. VK4 marks no
// invalid point. The pixel is x (y) length per pixel; Gwyddion spreads the field over (width - 1) pixels instead
// ("from comparison with original software"), so its pixel is width / (width - 1) times smaller.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

// Throws InputError naming the file and the field for anything wrong with it.
HeightMap ReadKeyenceVk4(const std::filesystem::path& path);
HeightMap ParseKeyenceVk4(const std::string& bytes, const std::string& name);
// True when `head` starts as a VK4 does ("VK4_", a version, four zero bytes).
bool HasKeyenceVk4Magic(const std::string& head);

}  // namespace fvm::imaging
