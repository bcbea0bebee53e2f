#include "imaging/io/keyence_vk4.h"

#include <cstdint>
#include <string_view>

#include "core/file_io.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr std::size_t kVk4OffsetTableAt = 12;
constexpr std::size_t kVk4ConditionsMinSize = 304;
constexpr std::size_t kVk4ImageHeaderSize = 796;  // 7 uint32 and a 768-byte palette
constexpr double kMmPerPicometre = 1e-9;
constexpr const char* kVk4Reexport = "the file is damaged or incomplete: save it from the VK software again";

enum Vk4Offset { kVk4Conditions = 0, kVk4Light = 3, kVk4Height = 6, kVk4Strings = 16 };

std::uint32_t Vk4Word(const std::string& bytes, std::size_t at) { return LoadBytes<std::uint32_t>(bytes.data() + at); }

struct Vk4Image {
  std::uint64_t width = 0, height = 0;
  std::uint32_t bit_depth = 0;
  std::size_t data_at = 0;

  std::uint32_t Count(const std::string& bytes, std::size_t i) const {
    const char* p = bytes.data() + data_at + i * (bit_depth / 8);
    if (bit_depth == 8) return static_cast<unsigned char>(*p);
    if (bit_depth == 16) return LoadBytes<std::uint16_t>(p);
    return LoadBytes<std::uint32_t>(p);
  }
};

// The image the offset table's entry `what` points to, checked against the file's size.
Vk4Image ReadVk4Image(const std::string& bytes, const std::string& name, std::uint32_t offset, const std::string& what) {
  if (offset > bytes.size() || bytes.size() - offset < kVk4ImageHeaderSize) {
    FailReading(name, "the offset table's " + what + " entry (" + std::to_string(offset) +
                          ") leaves no room for an image header before the end of the file (" +
                          std::to_string(bytes.size()) + " bytes); " + kVk4Reexport);
  }
  Vk4Image image;
  image.width = Vk4Word(bytes, offset);
  image.height = Vk4Word(bytes, offset + 4);
  image.bit_depth = Vk4Word(bytes, offset + 8);
  const std::uint32_t compression = Vk4Word(bytes, offset + 12);
  const std::uint64_t byte_size = Vk4Word(bytes, offset + 16);
  RequireGridSize(name, "its " + what + " image says", image.width, image.height, kVk4Reexport);
  if (image.bit_depth != 8 && image.bit_depth != 16 && image.bit_depth != 32) {
    FailReading(name, "its " + what + " image has bit depth " + std::to_string(image.bit_depth) +
                          "; VK4 images have 8, 16 or 32; " + kVk4Reexport);
  }
  if (compression != 0) {
    FailReading(name, "its " + what + " image is compressed (compression " + std::to_string(compression) +
                          "); fvm reads uncompressed VK4 images");
  }
  const std::uint64_t expected = image.width * image.height * (image.bit_depth / 8);
  if (byte_size != expected) {
    FailReading(name, "its " + what + " image says " + std::to_string(byte_size) + " bytes, but " +
                          std::to_string(image.width) + " x " + std::to_string(image.height) + " at " +
                          std::to_string(image.bit_depth) + " bits are " + std::to_string(expected) + "; " +
                          kVk4Reexport);
  }
  image.data_at = offset + kVk4ImageHeaderSize;
  if (bytes.size() - image.data_at < expected) {
    FailReading(name, "its " + what + " image needs " + std::to_string(expected) + " bytes after its header, but " +
                          std::to_string(bytes.size() - image.data_at) + " follow; " + kVk4Reexport);
  }
  return image;
}

// The title of the strings block, its UTF-16 units outside ASCII shown as '?'; empty when absent or cut.
std::string Vk4Title(const std::string& bytes, std::uint32_t offset) {
  if (offset == 0 || offset > bytes.size() || bytes.size() - offset < 4) return {};
  const std::uint64_t units = Vk4Word(bytes, offset);
  if (units > 256 || (bytes.size() - offset - 4) / 2 < units) return {};
  std::string title;
  for (std::uint64_t i = 0; i < units; ++i) {
    const std::uint16_t unit = LoadBytes<std::uint16_t>(bytes.data() + offset + 4 + 2 * i);
    title += unit >= 0x20 && unit < 0x7f ? static_cast<char>(unit) : '?';
  }
  return FixedText(title.data(), title.size());
}

}  // namespace

bool HasKeyenceVk4Magic(const std::string& head) {
  return head.size() >= 12 && head.compare(0, 4, "VK4_") == 0 && head.compare(8, 4, std::string(4, '\0')) == 0;
}

HeightMap ParseKeyenceVk4(const std::string& bytes, const std::string& name) {
  if (bytes.compare(0, 4, "VK4_") != 0) FailReading(name, "does not start with 'VK4_': not a Keyence VK4 file");
  if (bytes.size() < kVk4OffsetTableAt + 72) {
    FailReading(name, "the header and offset table (84 bytes) are cut short; " + std::string(kVk4Reexport));
  }
  if (!HasKeyenceVk4Magic(bytes.substr(0, 12))) {
    FailReading(name, "its file type (bytes 8-11) is not 0: an assembled (stitched) VK4, which fvm does not read; "
                      "export the stitched image as a single measurement");
  }
  const auto offset = [&](Vk4Offset entry) { return Vk4Word(bytes, kVk4OffsetTableAt + 4 * entry); };
  const std::uint32_t conditions = offset(kVk4Conditions);
  if (conditions > bytes.size() || bytes.size() - conditions < kVk4ConditionsMinSize) {
    FailReading(name, "the offset table's measurement-conditions entry (" + std::to_string(conditions) +
                          ") leaves no room for the 304-byte block before the end of the file (" +
                          std::to_string(bytes.size()) + " bytes); " + kVk4Reexport);
  }
  const std::uint32_t conditions_size = Vk4Word(bytes, conditions);
  if (conditions_size < kVk4ConditionsMinSize || conditions_size > bytes.size() - conditions) {
    FailReading(name, "the measurement conditions say they are " + std::to_string(conditions_size) +
                          " bytes, not between 304 and what the file holds after them; " + kVk4Reexport);
  }
  const std::uint32_t x_pm = Vk4Word(bytes, conditions + 168);
  const std::uint32_t y_pm = Vk4Word(bytes, conditions + 172);
  const std::uint32_t z_pm = Vk4Word(bytes, conditions + 176);
  if (x_pm == 0 || y_pm == 0 || z_pm == 0) {
    FailReading(name, "the measurement conditions' x_length_per_pixel, y_length_per_pixel or z_length_per_digit is "
                      "0 (" + std::to_string(x_pm) + ", " + std::to_string(y_pm) + ", " + std::to_string(z_pm) +
                          " pm); " + kVk4Reexport);
  }
  if (offset(kVk4Height) == 0) FailReading(name, "the offset table names no height image: a VK4 of images only");
  const Vk4Image heights = ReadVk4Image(bytes, name, offset(kVk4Height), "height");

  HeightMap map;
  map.size_x = static_cast<int>(heights.width);
  map.size_y = static_cast<int>(heights.height);
  map.dx_mm = x_pm * kMmPerPicometre;
  map.dy_mm = y_pm * kMmPerPicometre;
  const std::string title = Vk4Title(bytes, offset(kVk4Strings));
  map.source = "Keyence VK4" + (title.empty() ? std::string() : ", " + title);
  const std::size_t n = heights.width * heights.height;
  map.z_mm.resize(n);
  const double mm_per_count = z_pm * kMmPerPicometre;
  for (std::size_t i = 0; i < n; ++i) map.z_mm[i] = heights.Count(bytes, i) * mm_per_count;

  if (offset(kVk4Light) != 0) {
    const Vk4Image light = ReadVk4Image(bytes, name, offset(kVk4Light), "light");
    if (light.width == heights.width && light.height == heights.height) {
      map.intensity.resize(n);
      for (std::size_t i = 0; i < n; ++i) map.intensity[i] = static_cast<float>(light.Count(bytes, i));
    } else {
      map.notes.push_back("its light (intensity) image is " + std::to_string(light.width) + " x " +
                          std::to_string(light.height) + ", not the heights' grid: left out");
    }
  }
  return map;
}

HeightMap ReadKeyenceVk4(const std::filesystem::path& path) {
  return ParseKeyenceVk4(ReadFileBytes(path), path.string());
}

}  // namespace fvm::imaging
