#include "imaging/io/height_map_image.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/image_codec.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr std::string_view kDescriptionTag = "fvm height map";

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& problem) {
  FailReading(path.string(), problem);
}

// "fvm height map; dx_mm=0.001; dy_mm=0.001; ..." -> {dx_mm: 0.001, ...}; empty for other descriptions.
std::map<std::string, double> ParseDescription(std::string_view text) {
  std::map<std::string, double> values;
  if (text.substr(0, kDescriptionTag.size()) != kDescriptionTag) return values;
  size_t start = kDescriptionTag.size();
  while (start < text.size()) {
    const size_t end = std::min(text.find(';', start), text.size());
    const std::string_view item = TrimBlanks(text.substr(start, end - start));
    const size_t equals = item.find('=');
    if (equals != std::string_view::npos) {
      if (const std::optional<double> value = ParseDouble(item.substr(equals + 1))) {
        values[std::string(TrimBlanks(item.substr(0, equals)))] = *value;
      }
    }
    start = end + 1;
  }
  return values;
}

// Raw counts of one channel: integer images are read in their own type (the codec would otherwise scale them
// to 0..1), float images as double.
std::vector<double> ReadChannel(ImageFileReader& input, const std::filesystem::path& path, int channel,
                                std::size_t n) {
  std::vector<double> values(n);
  const auto read = [&](PixelType type, void* data) {
    // OpenImageIO 2.4 reports a truncated TIFF strip only as an error text, with the read itself succeeding.
    std::string error;
    const bool read = input.ReadPixels(channel, channel + 1, type, data, &error);
    if (!read || !error.empty()) {
      Fail(path, "cannot read the image data (" + error + "); the file is damaged or incomplete");
    }
  };
  const auto convert = [&](auto tag, PixelType type) {
    std::vector<decltype(tag)> raw(n);
    read(type, raw.data());
    for (std::size_t i = 0; i < n; ++i) values[i] = static_cast<double>(raw[i]);
  };
  switch (input.Header().type) {
    case PixelType::kUint8:
      convert(std::uint8_t{}, PixelType::kUint8);
      break;
    case PixelType::kInt8:
      convert(std::int8_t{}, PixelType::kInt8);
      break;
    case PixelType::kUint16:
      convert(std::uint16_t{}, PixelType::kUint16);
      break;
    case PixelType::kInt16:
      convert(std::int16_t{}, PixelType::kInt16);
      break;
    case PixelType::kUint32:
      convert(std::uint32_t{}, PixelType::kUint32);
      break;
    case PixelType::kInt32:
      convert(std::int32_t{}, PixelType::kInt32);
      break;
    default:
      read(PixelType::kDouble, values.data());
      break;
  }
  return values;
}

}  // namespace

void HeightMapImageOptions::Check() const {
  for (const double v : {dx_mm, dy_mm, z_scale_mm}) {
    if (!(v >= 0.0) || !std::isfinite(v)) {
      throw InputError(
          "image options: pixel size and z scale must be positive mm (or 0 to take them from the "
          "file), got " +
          FormatShortest(v));
    }
  }
  if (!std::isfinite(z_offset_mm)) throw InputError("image options: the z offset must be a finite number of mm");
}

HeightMap ReadHeightMapImage(const std::filesystem::path& path, const HeightMapImageOptions& options) {
  options.Check();
  const std::size_t file_bytes = CheckReadableFile(path);
  std::string error;
  const std::unique_ptr<ImageFileReader> input = LoadImageCodec("reading " + path.string()).open(path, &error);
  if (!input) {
    Fail(path, "cannot read it as an image (" + error + "); height-map images are single-channel TIFF, EXR or PNG files");
  }
  const ImageHeader& spec = input->Header();
  CheckPixelsFitFile(path, spec, file_bytes);
  if (spec.width < 1 || spec.height < 1 || spec.depth > 1 ||
      static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height) > kMaxPoints) {
    Fail(path, "is a " + std::to_string(spec.width) + " x " + std::to_string(spec.height) + " x " +
                   std::to_string(spec.depth) + " image, not a height map fvm can hold");
  }
  const int alpha = spec.alpha_channel;
  if (spec.channels > 2 || (spec.channels == 2 && alpha < 0)) {
    Fail(path, "has " + std::to_string(spec.channels) +
                   " channels (a colour rendering?); a height map has one grey channel, and optionally alpha: "
                   "export the heights themselves");
  }
  const int height_channel = alpha == 0 ? 1 : 0;

  const std::map<std::string, double> described = ParseDescription(spec.description);
  const auto described_value = [&](const std::string& key) -> std::optional<double> {
    const auto it = described.find(key);
    if (it == described.end() || !std::isfinite(it->second)) return std::nullopt;
    return it->second;
  };
  // A resolution in pixels per centimetre is a deliberate statement about the sample; see the header.
  const auto resolution = [&](float per_cm) -> std::optional<double> {
    if (spec.resolution_unit != "cm" || !(per_cm > 0.0f)) return std::nullopt;
    return 10.0 / static_cast<double>(per_cm);
  };
  double dx = options.dx_mm;
  double dy = options.dy_mm > 0.0 ? options.dy_mm : options.dx_mm;
  if (dx == 0.0) {
    const std::optional<double> file_dx =
        described_value("dx_mm") ? described_value("dx_mm") : resolution(spec.x_resolution);
    std::optional<double> file_dy = described_value("dy_mm") ? described_value("dy_mm") : resolution(spec.y_resolution);
    if (!file_dx || !(*file_dx > 0.0)) {
      Fail(path, "the image does not say its pixel size; give it, e.g. --pixel-mm 0.00175 (mm)");
    }
    dx = *file_dx;
    if (dy == 0.0) dy = file_dy && *file_dy > 0.0 ? *file_dy : dx;
  }
  const bool integer = IsIntegerPixelType(spec.type);
  double z_scale = options.z_scale_mm;
  double z_offset = options.z_offset_mm;
  if (z_scale == 0.0) {
    if (const std::optional<double> scale = described_value("z_scale_mm"); scale && *scale > 0.0) {
      z_scale = *scale;
      z_offset = described_value("z_offset_mm").value_or(0.0);
    } else if (integer) {
      Fail(path, "holds " + spec.type_name +
                     " grey levels but does not say how many mm one level is; give it, e.g. --z-scale-mm 0.0001 (mm)");
    } else {
      z_scale = 1.0;  // float images hold mm
    }
  }

  const std::size_t n = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  const std::vector<double> raw = ReadChannel(*input, path, height_channel, n);
  std::vector<double> coverage;
  if (alpha >= 0) coverage = ReadChannel(*input, path, alpha, n);
  HeightMap map;
  map.size_x = spec.width;
  map.size_y = spec.height;
  map.dx_mm = dx;
  map.dy_mm = dy;
  map.x0_mm = described_value("x0_mm").value_or(0.0);
  map.y0_mm = described_value("y0_mm").value_or(0.0);
  map.source = "image (" + spec.format_name + ", " + spec.type_name + ")";
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool invalid = !std::isfinite(raw[i]) || (options.invalid_value && raw[i] == *options.invalid_value) ||
                         (!coverage.empty() && coverage[i] == 0.0);
    map.z_mm[i] = invalid ? std::numeric_limits<double>::quiet_NaN() : z_offset + z_scale * raw[i];
  }
  return map;
}

void WriteHeightMapImage(const std::filesystem::path& path, const HeightMap& map) {
  if (map.size_x < 1 || map.size_y < 1 ||
      map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y) ||
      !(map.dx_mm > 0.0) || !(map.dy_mm > 0.0)) {
    throw std::invalid_argument("height-map image writer: the height map is malformed (sizes, spacing or count)");
  }
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".tif" && extension != ".tiff" && extension != ".exr") {
    throw InputError(path.string() +
                     ": height-map images are written as float32 TIFF (.tif) or OpenEXR (.exr); "
                     "choose one of these extensions");
  }
  ImageWriteSpec spec;
  spec.width = map.size_x;
  spec.height = map.size_y;
  spec.type = PixelType::kFloat;
  spec.description = std::string(kDescriptionTag) + "; dx_mm=" + FormatShortest(map.dx_mm) +
                     "; dy_mm=" + FormatShortest(map.dy_mm) + "; x0_mm=" + FormatShortest(map.x0_mm) +
                     "; y0_mm=" + FormatShortest(map.y0_mm) + "; z_scale_mm=1; z_offset_mm=0; z in mm, NaN invalid";
  spec.x_resolution = static_cast<float>(10.0 / map.dx_mm);
  spec.y_resolution = static_cast<float>(10.0 / map.dy_mm);
  spec.resolution_unit = "cm";
  // The image holds float32 heights (TIFF and EXR float samples): the map's doubles rounded once here.
  const std::vector<float> heights(map.z_mm.begin(), map.z_mm.end());
  WriteImageFile(path, spec, PixelType::kFloat, heights.data());
}

}  // namespace fvm::imaging
