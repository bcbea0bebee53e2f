#pragma once
// Tile images for registration: one grey channel of float, row-major (row 0 at the top = highest Y), read and
// written through OpenImageIO (TIFF, PNG, EXR, ...; 8- and 16-bit integer and float pixels).

#include <Eigen/Core>
#include <filesystem>

namespace fvm::imaging {

using TileImage = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

enum class TilePixelType { kUint8, kUint16, kFloat };

// Integer pixels come back in their native counts (0..255, 0..65535), floats as stored: registration is blind to
// gain and offset. Colour tiles are averaged to grey; an alpha channel is ignored. `type`, when given, receives
// the stored pixel type (other integer types count as float). NaN pixels are invalid points (a height map's steep
// flanks); registration and fusing leave them out. Throws InputError naming the file when it is missing, empty,
// not an image, a volume, holds infinite pixels or no valid one.
TileImage ReadTileImage(const std::filesystem::path& path, TilePixelType* type = nullptr);

// The image's width and height (x, y) as its header gives them, no pixel decoded (the pitch of a Fiji tile
// configuration). Throws InputError naming the file when it is missing or not an image.
Eigen::Vector2i ReadTileImageSize(const std::filesystem::path& path);

// Writes atomically; integer types round and clamp. Throws InputError naming the file when it cannot be written.
void WriteTileImage(const std::filesystem::path& path, const TileImage& image, TilePixelType type);

}  // namespace fvm::imaging
