#include "imaging/io/tile_image.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/file_io.h"

namespace fvm::imaging {

TileImage ReadTileImage(const std::filesystem::path& path, TilePixelType* type) {
  CheckReadableFile(path);
  std::unique_ptr<OIIO::ImageInput> input = OIIO::ImageInput::open(path.string());
  if (!input) {
    throw InputError(path.string() + ": cannot read it as an image (" + OIIO::geterror() +
                     "); tiles are grey or colour TIFF, PNG or EXR files");
  }
  const OIIO::ImageSpec& spec = input->spec();
  // 2^28 pixels is 1 GB of floats: beyond any microscope camera, so a corrupt header, not a tile.
  if (spec.width < 1 || spec.height < 1 || spec.depth > 1 ||
      static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height) > (std::uint64_t{1} << 28)) {
    throw InputError(path.string() + ": a " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                     " x " + std::to_string(spec.depth) + " image is not a tile fvm can register");
  }
  const int channels = spec.nchannels;
  std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * channels);
  // Reading as FLOAT converts integers to 0..1; scaling back keeps native counts, which reads better in messages
  // and makes no difference to registration.
  if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data())) {
    throw InputError(path.string() + ": cannot read the pixels (" + input->geterror() + "); is the file truncated?");
  }
  double scale = 1.0;
  TilePixelType stored = TilePixelType::kFloat;
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8: scale = 255.0, stored = TilePixelType::kUint8; break;
    case OIIO::TypeDesc::UINT16: scale = 65535.0, stored = TilePixelType::kUint16; break;
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
  const OIIO::TypeDesc format = type == TilePixelType::kUint8    ? OIIO::TypeDesc::UINT8
                                : type == TilePixelType::kUint16 ? OIIO::TypeDesc::UINT16
                                                                 : OIIO::TypeDesc::FLOAT;
  const double scale = type == TilePixelType::kUint8 ? 255.0 : type == TilePixelType::kUint16 ? 65535.0 : 1.0;
  // OIIO converts float 0..1 to the integer range; clamp so that out-of-range values saturate, not wrap.
  std::vector<float> data(static_cast<size_t>(image.size()));
  for (Eigen::Index i = 0; i < image.size(); ++i) {
    const double v = image.data()[i] / scale;
    data[static_cast<size_t>(i)] = static_cast<float>(scale == 1.0 ? v : std::clamp(v, 0.0, 1.0));
  }
  OIIO::ImageSpec spec(static_cast<int>(image.cols()), static_cast<int>(image.rows()), 1, format);
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    std::unique_ptr<OIIO::ImageOutput> output = OIIO::ImageOutput::create(temporary.string());
    if (!output) throw InputError(path.string() + ": cannot write this image type (" + OIIO::geterror() + ")");
    if (!output->open(temporary.string(), spec) || !output->write_image(OIIO::TypeDesc::FLOAT, data.data()) ||
        !output->close()) {
      throw InputError(path.string() + ": cannot write (" + output->geterror() +
                       "); check that the directory exists and is writable");
    }
  });
}

}  // namespace fvm::imaging
