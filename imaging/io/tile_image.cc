#include "imaging/io/tile_image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/file_io.h"
#include "imaging/io/image_codec.h"

namespace fvm::imaging {

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
  const int channels = spec.channels;
  std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * channels);
  // Reading as FLOAT converts integers to 0..1; scaling back keeps native counts, which reads better in messages
  // and makes no difference to registration.
  if (!input->ReadPixels(0, channels, PixelType::kFloat, pixels.data(), &error)) {
    throw InputError(path.string() + ": cannot read the pixels (" + error + "); is the file truncated?");
  }
  double scale = 1.0;
  TilePixelType stored = TilePixelType::kFloat;
  switch (spec.type) {
    case PixelType::kUint8: scale = 255.0, stored = TilePixelType::kUint8; break;
    case PixelType::kUint16: scale = 65535.0, stored = TilePixelType::kUint16; break;
    default: break;
  }
  if (type != nullptr) *type = stored;
  const int alpha = spec.alpha_channel;
  const int grey_channels = alpha >= 0 && channels > 1 ? channels - 1 : channels;
  TileImage image(spec.height, spec.width);
  for (int y = 0; y < spec.height; ++y) {
    for (int x = 0; x < spec.width; ++x) {
      const float* p = &pixels[(static_cast<size_t>(y) * spec.width + x) * channels];
      double sum = 0.0;
      for (int c = 0; c < channels; ++c) {
        if (c != alpha || channels == 1) sum += p[c];
      }
      image(y, x) = static_cast<float>(sum / grey_channels * scale);
    }
  }
  // NaN marks an invalid point, as focus-variation height maps export steep flanks; infinity marks nothing.
  if (image.array().isInf().any()) {
    throw InputError(path.string() + ": holds infinite pixels; mark invalid points as NaN");
  }
  if (image.array().isNaN().all()) throw InputError(path.string() + ": holds no valid pixel");
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
