#include "imaging/io/focus_stack_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <variant>

#include "core/input_error.h"
#include "core/file_io.h"
#include "core/csv.h"
#include "core/number_text.h"
#include "imaging/io/image_codec.h"

namespace fvm::imaging {
namespace {

// A focus-variation stack has tens to hundreds of images; a list beyond this is a mistake, refused before the
// images are read.
constexpr std::size_t kMaxStackImages = 10000;

}  // namespace

std::vector<FocusStackEntry> ReadFocusStackList(const std::filesystem::path& list) {
  CsvOptions options;
  options.expected_header = "file,z_mm";
  options.max_bytes = std::size_t{1} << 26;
  options.max_rows = kMaxStackImages;
  const CsvTable table = ReadCsv(list, options);
  const int file_column = table.Require("file");
  int z_column = table.Optional("z_mm");  // "z" is accepted too; the message asks for the documented name
  if (z_column < 0) z_column = table.Optional("z");
  if (z_column < 0) z_column = table.Require("z_mm");
  std::vector<FocusStackEntry> entries;
  for (const CsvRow& row : table.rows()) {
    const std::string_view name = table.Text(row, file_column);
    if (name.empty()) table.Fail(row, "no image file named; expected 'file,z_mm'");
    const double z = table.Double(row, z_column);
    const std::string_view z_text = table.Text(row, z_column);
    std::filesystem::path file{std::string(name)};
    if (file.is_relative()) file = list.parent_path() / file;
    if (!entries.empty()) {
      const double step = z - entries.back().z_mm;
      if (step == 0.0) {
        table.Fail(row, "z = " + std::string(z_text) + " mm repeats line " + std::to_string(entries.back().line) +
                            "; each image of a stack needs its own z");
      }
      if (entries.size() >= 2 && (step > 0.0) != (entries[1].z_mm > entries[0].z_mm)) {
        table.Fail(row, "z = " + std::string(z_text) +
                            " mm is out of order; list the images by increasing or decreasing z");
      }
    }
    entries.push_back({file, z, row.line, list});
  }
  if (entries.size() < 3) {
    throw InputError(list.string() + ": " + std::to_string(entries.size()) +
                     " image(s); a focus stack needs at least 3 (a focus peak needs an image on either side)");
  }
  return entries;
}

namespace {

// An image file opened for its pixels, its header checked against the file's size, refused unless 2-D.
std::unique_ptr<ImageFileReader> OpenStackImage(const std::filesystem::path& path) {
  const std::size_t file_bytes = CheckReadableFile(path);
  std::string error;
  std::unique_ptr<ImageFileReader> input = LoadImageCodec("reading " + path.string()).open(path, &error);
  if (!input) throw InputError(path.string() + ": cannot read the image (" + error + ")");
  const ImageHeader& spec = input->Header();
  CheckPixelsFitFile(path, spec, file_bytes);
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.channels < 1) {
    throw InputError(path.string() + ": not a 2D image");
  }
  return input;
}

void ReadChannels(ImageFileReader& input, const std::filesystem::path& path, int channels, PixelType type,
                  void* data) {
  std::string error;
  if (!input.ReadPixels(0, channels, type, data, &error) || !error.empty()) {
    throw InputError(path.string() + ": cannot read the image data; the file is damaged or incomplete");
  }
}

}  // namespace

StackImage ReadStackImage(const std::filesystem::path& path) {
  const std::unique_ptr<ImageFileReader> input = OpenStackImage(path);
  const ImageHeader& spec = input->Header();
  StackImage image;
  image.width = spec.width;
  image.height = spec.height;
  const std::size_t n = std::size_t(spec.width) * std::size_t(spec.height);
  const auto read = [&](PixelType type, void* data, int channels) { ReadChannels(*input, path, channels, type, data); };
  if (spec.channels == 1 && spec.type == PixelType::kUint8) {
    std::vector<std::uint8_t> pixels(n);
    read(PixelType::kUint8, pixels.data(), 1);
    image.pixels = std::move(pixels);
  } else if (spec.channels == 1 && spec.type == PixelType::kUint16) {
    std::vector<std::uint16_t> pixels(n);
    read(PixelType::kUint16, pixels.data(), 1);
    image.pixels = std::move(pixels);
  } else {
    // Float, other integer types and colour: grey as float, in the file's own scale (the codec maps integer
    // types to 0..1, which does not matter: the focus peak does not depend on the scale).
    const int channels = std::min(spec.channels, 3);
    std::vector<float> all(n * std::size_t(channels));
    read(PixelType::kFloat, all.data(), channels);
    std::vector<float> grey(n);
    for (std::size_t i = 0; i < n; ++i) {
      float sum = 0.0f;
      for (int c = 0; c < channels; ++c) sum += all[i * std::size_t(channels) + std::size_t(c)];
      grey[i] = sum / static_cast<float>(channels);
    }
    image.pixels = std::move(grey);
  }
  return image;
}

StackImage ReadStackColour(const std::filesystem::path& path) {
  const std::unique_ptr<ImageFileReader> input = OpenStackImage(path);
  const ImageHeader& spec = input->Header();
  StackImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.channels >= 3 ? 3 : 1;
  const std::size_t n = std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(image.channels);
  const auto read = [&](PixelType type, void* data) { ReadChannels(*input, path, image.channels, type, data); };
  if (spec.type == PixelType::kUint8) {
    std::vector<std::uint8_t> pixels(n);
    read(PixelType::kUint8, pixels.data());
    image.pixels = std::move(pixels);
  } else {
    std::vector<float> pixels(n);
    read(PixelType::kFloat, pixels.data());
    image.pixels = std::move(pixels);
  }
  return image;
}

std::vector<FocusStackEntry> FocusStackFromImages(const std::vector<std::filesystem::path>& paths, double step_mm) {
  if (paths.size() < 3) {
    throw InputError(std::to_string(paths.size()) +
                     " image(s); a focus stack needs at least 3 (a focus peak needs an image on either side)");
  }
  if (paths.size() > kMaxStackImages) {
    throw InputError(std::to_string(paths.size()) + " images; a focus stack has at most " +
                     std::to_string(kMaxStackImages));
  }
  if (!(step_mm != 0.0) || !std::isfinite(step_mm)) throw InputError("the z step must be a finite non-zero number");
  std::vector<FocusStackEntry> entries;
  for (std::size_t i = 0; i < paths.size(); ++i) entries.push_back({paths[i], double(i) * step_mm, 0, {}});
  return entries;
}

void WriteStackImage(const std::filesystem::path& path, const StackImage& image) {
  const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
  const auto [type, data, size] = std::visit(
      [](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        const PixelType t = std::is_same_v<T, std::uint8_t>    ? PixelType::kUint8
                            : std::is_same_v<T, std::uint16_t> ? PixelType::kUint16
                                                               : PixelType::kFloat;
        return std::tuple(t, static_cast<const void*>(v.data()), v.size());
      },
      image.pixels);
  if (image.width <= 0 || image.height <= 0 || size != n * std::size_t(std::max(image.channels, 1))) {
    throw InputError(path.string() + ": the image is empty or its pixel count does not match its size");
  }
  if (image.channels != 1 && image.channels != 3) {
    throw InputError(path.string() + ": an image of 1 or 3 channels is written, not " + std::to_string(image.channels));
  }
  ImageWriteSpec spec;
  spec.width = image.width;
  spec.height = image.height;
  spec.channels = image.channels;
  spec.type = type;
  WriteImageFile(path, spec, type, data);
}

}  // namespace fvm::imaging
