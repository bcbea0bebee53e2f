#include "imaging/io/sdf.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string_view>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little,
              "binary SDF is little-endian and is copied as it is; add byte swapping for this platform");

constexpr std::size_t kBinaryHeaderSize = 81;

// What the header says, in either form.
struct SdfHeader {
  std::string manufacturer;
  std::uint64_t points = 0, profiles = 0;
  double x_scale = 0, y_scale = 0, z_scale = 0;
  int compression = 0;
  int data_type = 7;
};

HeightMap MakeMap(const std::string& name, const SdfHeader& h, const std::string& form) {
  if (h.points < 1 || h.profiles < 1) FailReading(name, "NumPoints and NumProfiles must be at least 1");
  if (h.points * h.profiles > kMaxPoints) FailReading(name, "more points than fvm can hold");
  if (!(h.x_scale > 0) || !(h.y_scale > 0) || !std::isfinite(h.x_scale) || !std::isfinite(h.y_scale)) {
    FailReading(name, "Xscale and Yscale (the point spacing in metres) must be positive");
  }
  if (!std::isfinite(h.z_scale) || h.z_scale == 0)
    FailReading(name, "Zscale (metres per unit of height) must be finite and non-zero");
  if (h.compression != 0) {
    FailReading(
        name, "Compression = " + std::to_string(h.compression) + ": compressed SDF is not read; save it uncompressed");
  }
  HeightMap map;
  map.size_x = static_cast<int>(h.points);
  map.size_y = static_cast<int>(h.profiles);
  map.dx_mm = h.x_scale * kMmPerMetre;
  map.dy_mm = h.y_scale * kMmPerMetre;
  map.source = "ISO 25178-71 SDF (" + form + ")" + (h.manufacturer.empty() ? "" : ", " + h.manufacturer);
  return map;
}

// A value in mm; NaN stays an invalid point, a height that overflows is an error, not an infinity.
double Height(const std::string& name, double value, double z_scale) {
  if (std::isnan(value)) return value;
  const double mm = value * z_scale * kMmPerMetre;
  if (!std::isfinite(mm))
    FailReading(name, "a height of " + FormatShortest(value) + " x Zscale " + FormatShortest(z_scale) +
                          " m is not a finite number");
  return mm;
}

HeightMap ParseAscii(std::string_view text, const std::string& name) {
  SdfHeader h;
  bool seen[6] = {};  // NumPoints, NumProfiles, Xscale, Yscale, Zscale, DataType
  if (text.find('\n') == std::string_view::npos) FailReading(name, "holds only its first line; the file is cut short");
  std::size_t start = text.find('\n') + 1, line_number = 1;
  bool header_done = false;
  while (start < text.size() && !header_done) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line = TrimBlanks(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    const std::string where = "line " + std::to_string(line_number);
    if (line == "*") {
      header_done = true;
      break;
    }
    if (line.empty()) continue;
    const std::size_t eq = line.find('=');
    if (eq == std::string_view::npos)
      FailReading(name,
                  where + ": '" + QuotedForMessage(line) + "' is not 'Key = value' (the header ends at a line '*')");
    const std::string key(TrimBlanks(line.substr(0, eq)));
    const std::string_view value = TrimBlanks(line.substr(eq + 1));
    const auto number = [&]() {
      const std::optional<double> v = ParseDouble(value);
      if (!v) FailReading(name, where + ": " + key + " = " + QuotedForMessage(value) + " is not a number");
      return *v;
    };
    const auto count = [&]() {
      const std::optional<std::int64_t> v = ParseInt(value);
      if (!v || *v < 1 || *v > 65535) FailReading(name, where + ": " + key + " must be a whole number from 1 to 65535");
      return static_cast<std::uint64_t>(*v);
    };
    const auto small = [&]() {  // Compression, DataType: a byte in the binary form
      const std::optional<std::int64_t> v = ParseInt(value);
      if (!v || *v < 0 || *v > 255) FailReading(name, where + ": " + key + " must be a whole number from 0 to 255");
      return static_cast<int>(*v);
    };
    if (key == "ManufacID") h.manufacturer = std::string(value);
    else if (key == "NumPoints") h.points = count(), seen[0] = true;
    else if (key == "NumProfiles") h.profiles = count(), seen[1] = true;
    else if (key == "Xscale") h.x_scale = number(), seen[2] = true;
    else if (key == "Yscale") h.y_scale = number(), seen[3] = true;
    else if (key == "Zscale") h.z_scale = number(), seen[4] = true;
    else if (key == "Compression") h.compression = small();
    else if (key == "DataType") h.data_type = small(), seen[5] = true;
  }
  if (!header_done) FailReading(name, "the header has no closing line '*'; the file is cut short");
  const char* keys[5] = {"NumPoints", "NumProfiles", "Xscale", "Yscale", "Zscale"};
  for (int k = 0; k < 5; ++k) {
    if (!seen[k]) FailReading(name, std::string("the header has no ") + keys[k]);
  }
  HeightMap map = MakeMap(name, h, "aISO-1.0");
  const std::size_t wanted = h.points * h.profiles;
  map.z_mm.reserve(std::min(wanted, text.size() / 2));  // a value takes 2 characters at least: no trust in the header
  // The data: numbers separated by white space, up to a '*' (or the end of the file).
  while (start < text.size() && map.z_mm.size() < wanted) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line = TrimBlanks(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line == "*") break;
    for (const std::string_view word : SplitWords(line)) {
      const std::optional<double> v = ParseDouble(word);
      if (!v) {
        FailReading(name, "line " + std::to_string(line_number) + ": " + QuotedForMessage(word) +
                              " is not a number; the data are numbers separated by blanks, ended by a line '*'");
      }
      if (map.z_mm.size() == wanted)
        FailReading(name, "line " + std::to_string(line_number) + ": more values than NumPoints x NumProfiles");
      map.z_mm.push_back(Height(name, *v, h.z_scale));
    }
  }
  if (map.z_mm.size() != wanted) {
    FailReading(name, std::to_string(map.z_mm.size()) +
                          " values where NumPoints x NumProfiles = " + std::to_string(h.points) + " x " +
                          std::to_string(h.profiles) + " need " + std::to_string(wanted) + "; the file is cut short");
  }
  return map;
}

HeightMap ParseBinary(const std::string& bytes, const std::string& name) {
  if (bytes.size() < kBinaryHeaderSize)
    FailReading(name, "shorter than the 81-byte binary SDF header; the file is cut short");
  const char* p = bytes.data();
  SdfHeader h;
  const std::string_view id(p + 8, 10);
  h.manufacturer = std::string(TrimBlanks(id.substr(0, id.find('\0'))));
  h.points = LoadBytes<std::uint16_t>(p + 42);
  h.profiles = LoadBytes<std::uint16_t>(p + 44);
  h.x_scale = LoadBytes<double>(p + 46);
  h.y_scale = LoadBytes<double>(p + 54);
  h.z_scale = LoadBytes<double>(p + 62);
  h.compression = static_cast<unsigned char>(p[78]);
  h.data_type = static_cast<unsigned char>(p[79]);
  static constexpr std::size_t kSizes[8] = {1, 2, 4, 4, 1, 2, 4, 8};
  if (h.data_type > 7) {
    FailReading(name,
                "DataType " + std::to_string(h.data_type) + " is not one of SDF's 0-7 (integers, float32, float64)");
  }
  HeightMap map = MakeMap(name, h, "bISO-1.0");
  const std::size_t size = kSizes[h.data_type];
  const std::size_t count = h.points * h.profiles;
  if (bytes.size() - kBinaryHeaderSize < count * size) {
    FailReading(name, "the data hold " + std::to_string((bytes.size() - kBinaryHeaderSize) / size) + " values where " +
                          std::to_string(h.points) + " x " + std::to_string(h.profiles) +
                          " are declared; the file is cut short");
  }
  map.z_mm.reserve(count);  // the bytes are there (checked above)
  for (std::size_t i = 0; i < count; ++i) {
    const char* v = p + kBinaryHeaderSize + i * size;
    double value = 0;
    switch (h.data_type) {
      case 0:
        value = LoadBytes<std::uint8_t>(v);
        break;
      case 1:
        value = LoadBytes<std::uint16_t>(v);
        break;
      case 2:
        value = LoadBytes<std::uint32_t>(v);
        break;
      case 3:
        value = LoadBytes<float>(v);
        break;
      case 4:
        value = LoadBytes<std::int8_t>(v);
        break;
      case 5:
        value = LoadBytes<std::int16_t>(v);
        break;
      case 6:
        value = LoadBytes<std::int32_t>(v);
        break;
      default:
        value = LoadBytes<double>(v);
        break;
    }
    map.z_mm.push_back(Height(name, value, h.z_scale));
  }
  return map;
}

}  // namespace

HeightMap ParseSdf(const std::string& bytes, const std::string& name) {
  const std::string_view magic = std::string_view(bytes).substr(0, 8);
  if (magic == "aISO-1.0") return ParseAscii(bytes, name);
  if (magic == "bISO-1.0") return ParseBinary(bytes, name);
  FailReading(name, "not an ISO 25178-71 SDF file (it starts with neither aISO-1.0 nor bISO-1.0)");
}

HeightMap ReadSdf(const std::filesystem::path& path) { return ParseSdf(ReadFileBytes(path), path.string()); }

}  // namespace fvm::imaging
