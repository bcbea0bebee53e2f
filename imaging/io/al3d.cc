#include "imaging/io/al3d.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little,
              "AL3D depth data is little-endian and is copied as it is; add byte swapping for this platform");

constexpr std::string_view kMagic("AliconaImaging\0\r\n", 17);
constexpr std::size_t kKeySize = 20;
constexpr std::size_t kValueSize = 30;
constexpr std::size_t kTagSize = kKeySize + kValueSize + 2;  // key, value, CRLF
constexpr std::size_t kCommentSize = 256;
constexpr const char* kAl3dReexport = "the file is damaged or incomplete: export it from the instrument again";

struct Tag {
  std::string key;
  std::string value;
};

// A field is NUL-terminated within its size; the rest is padding.
std::string Field(std::string_view bytes) { return std::string(bytes.substr(0, bytes.find('\0'))); }

Tag ParseTag(const std::string& name, std::string_view bytes, std::size_t index) {
  const std::string_view key = bytes.substr(0, kKeySize);
  const std::string_view value = bytes.substr(kKeySize, kValueSize);
  const std::string where = "header tag " + std::to_string(index + 1);
  if (key[kKeySize - 1] != '\0' || key[0] == '\0' || value[kValueSize - 1] != '\0') {
    FailReading(name, where + " is not a NUL-terminated key and value; " + kAl3dReexport);
  }
  if (bytes.substr(kKeySize + kValueSize, 2) != "\r\n") {
    FailReading(name, where + " ('" + Field(key) + "') does not end in CR LF; " + kAl3dReexport);
  }
  return {Field(key), Field(value)};
}

class Header {
 public:
  Header(const std::string& name, const std::vector<Tag>& tags) : name_(name), tags_(tags) {}

  const Tag* Find(const std::string& key) const {
    for (const Tag& tag : tags_) {
      if (tag.key == key) return &tag;
    }
    return nullptr;
  }
  std::optional<double> Number(const std::string& key) const {
    const Tag* tag = Find(key);
    if (!tag) return std::nullopt;
    const std::optional<double> value = ParseDouble(tag->value);
    if (!value) FailReading(name_, "header tag " + key + " is '" + tag->value + "', not a number; " + kAl3dReexport);
    return value;
  }
  double RequiredNumber(const std::string& key) const {
    const std::optional<double> value = Number(key);
    if (!value)
      FailReading(name_, "the header has no " + key + " tag, which every AL3D depth image has; " + kAl3dReexport);
    return *value;
  }
  std::uint64_t RequiredCount(const std::string& key, std::uint64_t max) const {
    const Tag* tag = Find(key);
    if (!tag)
      FailReading(name_, "the header has no " + key + " tag, which every AL3D depth image has; " + kAl3dReexport);
    const std::optional<std::int64_t> value = ParseInt(tag->value);
    if (!value || *value < 0 || static_cast<std::uint64_t>(*value) > max) {
      FailReading(name_, "header tag " + key + " is '" + tag->value + "', not a count between 0 and " +
                             std::to_string(max) + "; " + kAl3dReexport);
    }
    return static_cast<std::uint64_t>(*value);
  }

 private:
  const std::string& name_;
  const std::vector<Tag>& tags_;
};

}  // namespace

HeightMap ParseAl3d(const std::string& bytes, const std::string& name) {
  if (bytes.empty()) FailReading(name, "the file is empty; export it again");
  if (bytes.size() < kMagic.size() || std::string_view(bytes).substr(0, kMagic.size()) != kMagic) {
    FailReading(name, "does not start with the AL3D signature 'AliconaImaging': not an Alicona AL3D file");
  }
  if (bytes.size() < kMagic.size() + 2 * kTagSize + kCommentSize)
    FailReading(name, "the AL3D header is truncated; " + std::string(kAl3dReexport));
  const std::string_view view(bytes);
  std::size_t pos = kMagic.size();
  const Tag version = ParseTag(name, view.substr(pos, kTagSize), 0);
  const Tag counter = ParseTag(name, view.substr(pos + kTagSize, kTagSize), 1);
  pos += 2 * kTagSize;
  if (version.key != "Version" || counter.key != "TagCount") {
    FailReading(name,
                "the AL3D header does not start with the Version and TagCount tags; " + std::string(kAl3dReexport));
  }
  const std::optional<std::int64_t> count = ParseInt(counter.value);
  const std::size_t room = (bytes.size() - pos - kCommentSize) / kTagSize;
  if (!count || *count < 0 || static_cast<std::uint64_t>(*count) > room) {
    FailReading(name, "TagCount is '" + counter.value + "' but the file has room for " + std::to_string(room) +
                          " tags; " + kAl3dReexport);
  }
  std::vector<Tag> tags;
  for (std::int64_t i = 0; i < *count; ++i, pos += kTagSize) {
    tags.push_back(ParseTag(name, view.substr(pos, kTagSize), static_cast<std::size_t>(i) + 2));
  }
  const std::string_view comment = view.substr(pos, kCommentSize);
  if (comment.substr(kCommentSize - 2) != "\r\n")
    FailReading(name, "the AL3D comment does not end in CR LF; " + std::string(kAl3dReexport));
  const std::size_t header_end = pos + kCommentSize;

  const Header header(name, tags);
  const std::uint64_t cols = header.RequiredCount("Cols", kMaxPoints);
  const std::uint64_t rows = header.RequiredCount("Rows", kMaxPoints);
  if (cols == 0 || rows == 0 || cols * rows > kMaxPoints) {
    FailReading(name, "Cols x Rows is " + std::to_string(cols) + " x " + std::to_string(rows) +
                          ", not a depth image fvm can hold; " + kAl3dReexport);
  }
  // The sign of the pixel size only says which way the image runs; Gwyddion reads it the same way.
  const double dx_m = std::fabs(header.RequiredNumber("PixelSizeXMeter"));
  const double dy_m = std::fabs(header.RequiredNumber("PixelSizeYMeter"));
  if (!(dx_m > 0.0) || !(dy_m > 0.0) || !std::isfinite(dx_m) || !std::isfinite(dy_m)) {
    FailReading(name, "PixelSizeXMeter / PixelSizeYMeter are not positive sizes; " + std::string(kAl3dReexport));
  }
  const std::optional<double> offset = header.Number("DepthImageOffset");
  if (!offset || *offset == 0.0) {
    FailReading(name,
                "holds no depth image (DepthImageOffset is missing or 0): export the measurement with its depth data");
  }
  const std::uint64_t stride = (cols * sizeof(float) + 7) / 8 * 8;
  const std::uint64_t image_bytes = rows * stride;
  if (*offset < static_cast<double>(header_end) || *offset != std::floor(*offset) ||
      *offset + static_cast<double>(image_bytes) > static_cast<double>(bytes.size())) {
    FailReading(name, "the depth image (" + std::to_string(rows) + " rows of " + std::to_string(stride) + " bytes at " +
                          "DepthImageOffset " + FormatShortest(*offset) + ") does not lie within the file's " +
                          std::to_string(bytes.size()) + " bytes; " + kAl3dReexport);
  }
  const auto depth_offset = static_cast<std::size_t>(*offset);
  const double invalid = header.Number("InvalidPixelValue").value_or(std::numeric_limits<double>::quiet_NaN());
  // A finite InvalidPixelValue is written with fewer digits than the float32 it marks ("3.40282e+038" for
  // FLT_MAX): compare to the six significant digits such values have. Real depths are nowhere near it.
  const double invalid_tolerance = 1e-5 * std::fabs(invalid);

  HeightMap map;
  map.size_x = static_cast<int>(cols);
  map.size_y = static_cast<int>(rows);
  map.dx_mm = dx_m * kMmPerMetre;
  map.dy_mm = dy_m * kMmPerMetre;
  map.source = "AL3D (Alicona), version " + version.value;
  map.z_mm.resize(static_cast<std::size_t>(cols * rows));
  for (std::size_t iy = 0; iy < rows; ++iy) {
    const char* row = bytes.data() + depth_offset + iy * stride;
    for (std::size_t ix = 0; ix < cols; ++ix) {
      float z_m;
      std::memcpy(&z_m, row + ix * sizeof(float), sizeof z_m);
      const bool bad = !std::isfinite(z_m) ||
                       (std::isfinite(invalid) && std::fabs(static_cast<double>(z_m) - invalid) <= invalid_tolerance);
      map.z_mm[iy * cols + ix] =
          bad ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(z_m) * kMmPerMetre;
    }
  }
  return map;
}

HeightMap ReadAl3d(const std::filesystem::path& path) { return ParseAl3d(ReadFileBytes(path), path.string()); }

std::string BuildAl3d(const HeightMap& map) {
  if (map.size_x < 1 || map.size_y < 1 ||
      map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y) ||
      !(map.dx_mm > 0.0) || !(map.dy_mm > 0.0)) {
    throw std::invalid_argument("AL3D writer: the height map is malformed (sizes, spacing or point count)");
  }
  const std::size_t cols = static_cast<std::size_t>(map.size_x);
  const std::size_t rows = static_cast<std::size_t>(map.size_y);
  const std::size_t stride = (cols * sizeof(float) + 7) / 8 * 8;
  constexpr std::size_t kTags = 9;
  const std::size_t header = kMagic.size() + (2 + kTags) * kTagSize + kCommentSize;
  const std::size_t depth_offset = (header + 7) / 8 * 8;  // aligned, as instrument files are

  std::string bytes(kMagic);
  const auto tag = [&](const std::string& key, const std::string& value) {
    std::string field(kTagSize, '\0');
    field.replace(0, key.size(), key);
    field.replace(kKeySize, value.size(), value);
    field.replace(kKeySize + kValueSize, 2, "\r\n");
    bytes += field;
  };
  tag("Version", "1");
  tag("TagCount", std::to_string(kTags));
  tag("Cols", std::to_string(cols));
  tag("Rows", std::to_string(rows));
  tag("NumberOfPlanes", "0");
  tag("PixelSizeXMeter", FormatShortest(map.dx_mm / kMmPerMetre));
  tag("PixelSizeYMeter", FormatShortest(map.dy_mm / kMmPerMetre));
  tag("InvalidPixelValue", "NaN");
  tag("DepthImageOffset", std::to_string(depth_offset));
  tag("TextureImageOffset", "0");
  tag("IconOffset", "0");
  std::string comment(kCommentSize, '\0');
  const std::string note = "written by fvm";
  comment.replace(0, note.size(), note);
  comment.replace(kCommentSize - 2, 2, "\r\n");
  bytes += comment;
  bytes.resize(depth_offset + rows * stride, '\0');
  for (std::size_t iy = 0; iy < rows; ++iy) {
    for (std::size_t ix = 0; ix < cols; ++ix) {
      const float z = map.z_mm[iy * cols + ix];
      const float z_m = std::isfinite(z) ? static_cast<float>(static_cast<double>(z) / kMmPerMetre)
                                         : std::numeric_limits<float>::quiet_NaN();
      std::memcpy(bytes.data() + depth_offset + iy * stride + ix * sizeof(float), &z_m, sizeof z_m);
    }
  }
  return bytes;
}

void WriteAl3d(const std::filesystem::path& path, const HeightMap& map) {
  WriteFileAtomically(path, BuildAl3d(map));
}

}  // namespace fvm::imaging
