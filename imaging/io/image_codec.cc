#include "imaging/io/image_codec.h"

#include <algorithm>
#include <cstdint>
#include <string>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/io/plugin_loader.h"

namespace fvm::imaging {

const ImageCodec& LoadImageCodec(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_image_oiio.so", "fvm_image_codec_v1", "OpenImageIO",
                                      "libopenimageio2.4"};
  return *static_cast<const ImageCodec*>(LoadPlugin(kPlugin, action));
}

void WriteImageFile(const std::filesystem::path& path, const ImageWriteSpec& spec, PixelType data_type,
                    const void* data) {
  const ImageCodec& codec = LoadImageCodec("writing " + path.string());
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    std::string error;
    switch (codec.write(temporary, spec, data_type, data, &error)) {
      case ImageWriteResult::kWritten:
        return;
      case ImageWriteResult::kUnknownFormat:
        throw InputError(path.string() + ": cannot write this image type (" + error + ")");
      case ImageWriteResult::kFailed:
        throw InputError(path.string() + ": cannot write (" + error +
                         "); check that the directory exists, is writable and has free space");
    }
  });
}

namespace {

std::uint64_t BytesPerValue(PixelType type) {
  switch (type) {
    case PixelType::kUint8:
    case PixelType::kInt8: return 1;
    case PixelType::kUint16:
    case PixelType::kInt16: return 2;
    case PixelType::kDouble: return 8;
    default: return 4;
  }
}

}  // namespace

void CheckPixelsFitFile(const std::filesystem::path& path, const ImageHeader& header, std::size_t file_bytes) {
  constexpr std::uint64_t kMaxCompression = 4096;
  constexpr std::uint64_t kAlwaysAllowed = std::uint64_t{64} << 20;
  constexpr std::uint64_t kDimensionLimit = std::uint64_t{1} << 20;  // no image is a million pixels wide
  const auto dimension = [](int v) { return static_cast<std::uint64_t>(v < 1 ? 1 : v); };
  const std::uint64_t w = dimension(header.width), h = dimension(header.height), d = dimension(header.depth),
                      c = dimension(header.channels);
  if (w > kDimensionLimit || h > kDimensionLimit || d > kDimensionLimit || c > 4096 ||
      w * h * d * c * BytesPerValue(header.type) >
          std::max(kAlwaysAllowed, kMaxCompression * static_cast<std::uint64_t>(file_bytes))) {
    throw InputError(path.string() + ": its header declares a " + std::to_string(header.width) + " x " +
                     std::to_string(header.height) + " x " + std::to_string(header.depth) + " image of " +
                     std::to_string(header.channels) + " channels, more than a file of " +
                     std::to_string(file_bytes) + " bytes can hold; the file is damaged");
  }
  // Each strip of a TIFF needs an offset and a byte count (4 bytes each at least) in the file. A damaged header
  // that declares thousands of strips in a few hundred bytes would otherwise have the library try each of them
  // (about 1 ms a strip: seconds for nothing).
  if (header.rows_per_strip > 0) {
    const std::uint64_t rows = static_cast<std::uint64_t>(header.rows_per_strip);
    const std::uint64_t strips = (h + rows - 1) / rows * d;
    if (strips * 8 > static_cast<std::uint64_t>(file_bytes)) {
      throw InputError(path.string() + ": its header declares " + std::to_string(strips) + " strips of " +
                       std::to_string(header.rows_per_strip) + " rows, more than a file of " +
                       std::to_string(file_bytes) + " bytes can index; the file is damaged");
    }
  }
}

}  // namespace fvm::imaging
