#include "imaging/io/tile_image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/input_error.h"
#include "core/file_io.h"
#include "imaging/io/image_codec.h"

namespace fvm::imaging {

namespace {

// The pixels read as T and averaged over the colour channels (an alpha channel left out) into `image`: 8- and
// 16-bit integers in their native counts; other types read as float (integers of other widths come back 0..1 from
// the library, as they always did).
template <typename T>
void ReadGrey(ImageFileReader& input, const ImageHeader& spec, PixelType as, const std::filesystem::path& path,
              TileImage& image) {
  const int channels = spec.channels;
  std::vector<T> pixels(static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height) * static_cast<size_t>(channels));
  std::string error;
  if (!input.ReadPixels(0, channels, as, pixels.data(), &error)) {
    throw InputError(path.string() + ": cannot read the pixels (" + error + "); is the file truncated?");
  }
  const int alpha = channels > 1 ? spec.alpha_channel : -1;
  const int grey_channels = alpha >= 0 ? channels - 1 : channels;
  const double factor = 1.0 / grey_channels;
  // Integers summed exactly; an alpha channel that is the last (as it almost always is) is simply not summed.
  using Sum = std::conditional_t<std::is_integral_v<T>, std::uint32_t, double>;
  const int summed = alpha < 0 || alpha == channels - 1 ? grey_channels : channels;
  const int skipped = summed == channels ? alpha : -1;
  float* out = image.data();
  const T* p = pixels.data();
  for (size_t i = 0, n = static_cast<size_t>(image.size()); i < n; ++i, p += channels) {
    Sum sum = 0;
    for (int c = 0; c < summed; ++c) sum += static_cast<Sum>(p[c]);
    if (skipped >= 0) sum -= static_cast<Sum>(p[skipped]);
    out[i] = static_cast<float>(static_cast<double>(sum) * factor);
  }
}

}  // namespace

Eigen::Vector2i ReadTileImageSize(const std::filesystem::path& path) {
  CheckReadableFile(path);
  std::string error;
  const std::unique_ptr<ImageFileReader> input = LoadImageCodec("reading " + path.string()).open(path, &error);
  if (!input) {
    throw InputError(path.string() + ": cannot read it as an image (" + error +
                     "); tiles are grey or colour TIFF, PNG or EXR files");
  }
  return Eigen::Vector2i(input->Header().width, input->Header().height);
}

TileImage ReadTileImage(const std::filesystem::path& path, TilePixelType* type) {
  const std::size_t file_bytes = CheckReadableFile(path);
  std::string error;
  const std::unique_ptr<ImageFileReader> input = LoadImageCodec("reading " + path.string()).open(path, &error);
  if (!input) {
    throw InputError(path.string() + ": cannot read it as an image (" + error +
                     "); tiles are grey or colour TIFF, PNG or EXR files");
  }
  const ImageHeader& spec = input->Header();
  CheckPixelsFitFile(path, spec, file_bytes);
  // 2^28 pixels is 1 GB of floats: beyond any microscope camera, so a corrupt header, not a tile.
  if (spec.width < 1 || spec.height < 1 || spec.depth > 1 ||
      static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height) > (std::uint64_t{1} << 28)) {
    throw InputError(path.string() + ": a " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                     " x " + std::to_string(spec.depth) + " image is not a tile fvm can register");
  }
  TilePixelType stored = TilePixelType::kFloat;
  if (spec.type == PixelType::kUint8) stored = TilePixelType::kUint8;
  if (spec.type == PixelType::kUint16) stored = TilePixelType::kUint16;
  if (type != nullptr) *type = stored;
  // 8- and 16-bit counts are read as they are stored (the library's conversion of every channel to float 0..1
  // cost more than the decoding of an uncompressed colour tile) and averaged to grey here; other types as float.
  TileImage image(spec.height, spec.width);
  switch (stored) {
    case TilePixelType::kUint8: ReadGrey<std::uint8_t>(*input, spec, PixelType::kUint8, path, image); break;
    case TilePixelType::kUint16: ReadGrey<std::uint16_t>(*input, spec, PixelType::kUint16, path, image); break;
    case TilePixelType::kFloat: ReadGrey<float>(*input, spec, PixelType::kFloat, path, image); break;
  }
  // NaN marks an invalid point, as focus-variation height maps export steep flanks; infinity marks nothing.
  // One pass (the array expressions for the two tests cost more than the grey average).
  bool infinite = false, valid = false;
  for (const float v : std::span<const float>(image.data(), static_cast<size_t>(image.size()))) {
    infinite = infinite || std::isinf(v);
    valid = valid || !std::isnan(v);
  }
  if (infinite) throw InputError(path.string() + ": holds infinite pixels; mark invalid points as NaN");
  if (!valid) throw InputError(path.string() + ": holds no valid pixel");
  return image;
}

void WriteTileImage(const std::filesystem::path& path, const TileImage& image, TilePixelType type) {
  const PixelType format = type == TilePixelType::kUint8    ? PixelType::kUint8
                           : type == TilePixelType::kUint16 ? PixelType::kUint16
                                                            : PixelType::kFloat;
  const double scale = type == TilePixelType::kUint8 ? 255.0 : type == TilePixelType::kUint16 ? 65535.0 : 1.0;
  // The codec converts float 0..1 to the integer range; clamp so that out-of-range values saturate, not wrap.
  std::vector<float> data(static_cast<size_t>(image.size()));
  for (Eigen::Index i = 0; i < image.size(); ++i) {
    const double v = image.data()[i] / scale;
    data[static_cast<size_t>(i)] = static_cast<float>(scale == 1.0 ? v : std::clamp(v, 0.0, 1.0));
  }
  ImageWriteSpec spec;
  spec.width = static_cast<int>(image.cols());
  spec.height = static_cast<int>(image.rows());
  spec.type = format;
  WriteImageFile(path, spec, PixelType::kFloat, data.data());
}

}  // namespace fvm::imaging
