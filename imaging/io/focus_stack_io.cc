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
#include "core/number_text.h"
#include "imaging/io/image_codec.h"

namespace fvm::imaging {
namespace {

std::string At(const std::filesystem::path& list, int line) { return list.string() + ":" + std::to_string(line); }

std::vector<std::string_view> SplitComma(std::string_view text) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    fields.push_back(TrimBlanks(text.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

}  // namespace

std::vector<FocusStackEntry> ReadFocusStackList(const std::filesystem::path& list) {
  const std::string text = ReadFileBytes(list, std::size_t{1} << 26);
  std::vector<FocusStackEntry> entries;
  int file_column = -1, z_column = -1;
  int line_number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view line = TrimBlanks(std::string_view(text).substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = SplitComma(line);
    if (file_column < 0) {
      for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i] == "file") file_column = static_cast<int>(i);
        if (fields[i] == "z_mm" || fields[i] == "z") z_column = static_cast<int>(i);
      }
      if (file_column < 0 || z_column < 0) {
        throw InputError(At(list, line_number) + ": the header must name the columns 'file' and 'z_mm' (found '" +
                         std::string(line) + "')");
      }
      continue;
    }
    if (static_cast<int>(fields.size()) <= std::max(file_column, z_column) || fields[file_column].empty()) {
      throw InputError(At(list, line_number) + ": expected 'file,z_mm', found '" + std::string(line) + "'");
    }
    const std::optional<double> z = ParseDouble(fields[z_column]);
    if (!z || !std::isfinite(*z)) {
      throw InputError(At(list, line_number) + ": z_mm '" + std::string(fields[z_column]) + "' is not a number");
    }
    std::filesystem::path file(std::string(fields[file_column]));
    if (file.is_relative()) file = list.parent_path() / file;
    if (!entries.empty()) {
      const double step = *z - entries.back().z_mm;
      if (step == 0.0) {
        throw InputError(At(list, line_number) + ": z = " + std::string(fields[z_column]) +
                         " mm repeats line " + std::to_string(entries.back().line) +
                         "; each image of a stack needs its own z");
      }
      if (entries.size() >= 2 && (step > 0.0) != (entries[1].z_mm > entries[0].z_mm)) {
        throw InputError(At(list, line_number) + ": z = " + std::string(fields[z_column]) +
                         " mm is out of order; list the images by increasing or decreasing z");
      }
    }
    entries.push_back({file, *z, line_number});
  }
  if (file_column < 0) throw InputError(list.string() + ": empty; expected a header 'file,z_mm' and one row per image");
  if (entries.size() < 3) {
    throw InputError(list.string() + ": " + std::to_string(entries.size()) +
                     " image(s); a focus stack needs at least 3 (a focus peak needs an image on either side)");
  }
  return entries;
}

StackImage ReadStackImage(const std::filesystem::path& path) {
  CheckReadableFile(path);
  std::string error;
  const std::unique_ptr<ImageFileReader> input = LoadImageCodec("reading " + path.string()).open(path, &error);
  if (!input) throw InputError(path.string() + ": cannot read the image (" + error + ")");
  const ImageHeader& spec = input->Header();
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.channels < 1) {
    throw InputError(path.string() + ": not a 2D image");
  }
  StackImage image;
  image.width = spec.width;
  image.height = spec.height;
  const std::size_t n = std::size_t(spec.width) * std::size_t(spec.height);
  const auto read = [&](PixelType type, void* data, int channels) {
    if (!input->ReadPixels(0, channels, type, data, &error) || !error.empty()) {
      throw InputError(path.string() + ": cannot read the image data; the file is damaged or incomplete");
    }
  };
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
  if (image.width <= 0 || image.height <= 0 || size != n) {
    throw InputError(path.string() + ": the image is empty or its pixel count does not match its size");
  }
  ImageWriteSpec spec;
  spec.width = image.width;
  spec.height = image.height;
  spec.type = type;
  const ImageCodec& codec = LoadImageCodec("writing " + path.string());
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    std::string error;
    switch (codec.write(temporary, spec, type, data, &error)) {
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

}  // namespace fvm::imaging
