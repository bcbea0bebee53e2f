#include "imaging/io/focus_stack_io.h"

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/input_error.h"
#include "core/file_io.h"
#include "core/number_text.h"

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
    std::filesystem::path file{std::string(fields[file_column])};  // braces: clang reads () as a declaration
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
  std::unique_ptr<OIIO::ImageInput> input = OIIO::ImageInput::open(path.string());
  if (!input) throw InputError(path.string() + ": cannot read the image (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.nchannels < 1) {
    throw InputError(path.string() + ": not a 2D image");
  }
  StackImage image;
  image.width = spec.width;
  image.height = spec.height;
  const std::size_t n = std::size_t(spec.width) * std::size_t(spec.height);
  const auto read = [&](OIIO::TypeDesc type, void* data, int channels) {
    if (!input->read_image(0, 0, 0, channels, type, data) || !input->geterror().empty()) {
      throw InputError(path.string() + ": cannot read the image data; the file is damaged or incomplete");
    }
  };
  if (spec.nchannels == 1 && spec.format.basetype == OIIO::TypeDesc::UINT8) {
    std::vector<std::uint8_t> pixels(n);
    read(OIIO::TypeDesc::UINT8, pixels.data(), 1);
    image.pixels = std::move(pixels);
  } else if (spec.nchannels == 1 && spec.format.basetype == OIIO::TypeDesc::UINT16) {
    std::vector<std::uint16_t> pixels(n);
    read(OIIO::TypeDesc::UINT16, pixels.data(), 1);
    image.pixels = std::move(pixels);
  } else {
    // Float, other integer types and colour: grey as float, in the file's own scale (OpenImageIO maps integer
    // types to 0..1, which does not matter: the focus peak does not depend on the scale).
    const int channels = std::min(spec.nchannels, 3);
    std::vector<float> all(n * std::size_t(channels));
    read(OIIO::TypeDesc::FLOAT, all.data(), channels);
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
        const OIIO::TypeDesc t = std::is_same_v<T, std::uint8_t>    ? OIIO::TypeDesc::UINT8
                                 : std::is_same_v<T, std::uint16_t> ? OIIO::TypeDesc::UINT16
                                                                    : OIIO::TypeDesc::FLOAT;
        return std::tuple(t, static_cast<const void*>(v.data()), v.size());
      },
      image.pixels);
  if (image.width <= 0 || image.height <= 0 || size != n) {
    throw InputError(path.string() + ": the image is empty or its pixel count does not match its size");
  }
  const OIIO::ImageSpec spec(image.width, image.height, 1, type);
  // Structured bindings copied into the lambda by name: clang 14 cannot capture them implicitly.
  WriteThroughTemporary(path, [&, type = type, data = data](const std::filesystem::path& temporary) {
    std::unique_ptr<OIIO::ImageOutput> output = OIIO::ImageOutput::create(temporary.string());
    if (!output) throw InputError(path.string() + ": cannot write this image type (" + OIIO::geterror() + ")");
    if (!output->open(temporary.string(), spec) || !output->write_image(type, data) || !output->close()) {
      throw InputError(path.string() + ": cannot write (" + output->geterror() +
                       "); check that the directory exists, is writable and has free space");
    }
  });
}

}  // namespace fvm::imaging
