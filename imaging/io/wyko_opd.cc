#include "imaging/io/wyko_opd.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string_view>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "OPD is little-endian and is copied as it is");

constexpr std::size_t kOpdEntrySize = 24;
constexpr std::size_t kOpdNameSize = 16;
constexpr std::size_t kOpdDirectoryAt = 2;
constexpr std::int16_t kOpdArrayType = 3;
constexpr std::int16_t kOpdInvalidInt16 = 32767;
constexpr float kOpdInvalidFloat = 1e38f;
constexpr const char* kOpdReexport = "the file is damaged or incomplete: save it from Vision again";

struct OpdBlock {
  std::int16_t type = 0;
  std::size_t at = 0;  // where its bytes start
  std::size_t length = 0;
};

class OpdBlocks {
 public:
  OpdBlocks(const std::string& bytes, const std::string& name) : bytes_(bytes), name_(name) {
    if (!HasWykoOpdDirectory(bytes)) {
      FailReading(name, "does not start with a Wyko OPD directory (the entry 'Directory' at byte 2): not an OPD file");
    }
    if (bytes.size() < kOpdDirectoryAt + kOpdEntrySize)
      FailReading(name, "the OPD directory is cut short; " + std::string(kOpdReexport));
    const std::int32_t directory_length = LoadBytes<std::int32_t>(bytes.data() + kOpdDirectoryAt + kOpdNameSize + 2);
    if (directory_length < static_cast<std::int32_t>(kOpdEntrySize) || directory_length % kOpdEntrySize != 0 ||
        static_cast<std::size_t>(directory_length) > bytes.size() - kOpdDirectoryAt) {
      FailReading(name, "the OPD directory's length is " + std::to_string(directory_length) +
                            ", not a whole number of 24-byte entries within the file's " +
                            std::to_string(bytes.size()) + " bytes; " + kOpdReexport);
    }
    std::size_t at = kOpdDirectoryAt + static_cast<std::size_t>(directory_length);
    for (std::size_t e = kOpdDirectoryAt + kOpdEntrySize; e < kOpdDirectoryAt + directory_length; e += kOpdEntrySize) {
      const std::string block_name = FixedText(bytes.data() + e, kOpdNameSize);
      const std::int16_t type = LoadBytes<std::int16_t>(bytes.data() + e + kOpdNameSize);
      const std::int32_t length = LoadBytes<std::int32_t>(bytes.data() + e + kOpdNameSize + 2);
      if (length < 0 || static_cast<std::size_t>(length) > bytes.size() - at) {
        FailReading(name, "block '" + QuotedForMessage(block_name) + "' says " + std::to_string(length) +
                              " bytes at byte " + std::to_string(at) + ", beyond the file's " +
                              std::to_string(bytes.size()) + "; " + kOpdReexport);
      }
      if (!block_name.empty()) blocks_.emplace(block_name, OpdBlock{type, at, static_cast<std::size_t>(length)});
      at += static_cast<std::size_t>(length);
    }
  }

  const OpdBlock* Find(const std::string& block) const {
    const auto it = blocks_.find(block);
    return it == blocks_.end() ? nullptr : &it->second;
  }

  // A number block (int16, or uint16 when asked, int32, float32 or float64, by its type and length).
  std::optional<double> Number(const std::string& block, bool unsigned_short = false) const {
    const OpdBlock* b = Find(block);
    if (!b) return std::nullopt;
    const char* p = bytes_.data() + b->at;
    if (b->type == 6 && b->length == 2) {
      return unsigned_short ? LoadBytes<std::uint16_t>(p) : LoadBytes<std::int16_t>(p);
    }
    if (b->type == 12 && b->length == 4) return LoadBytes<std::int32_t>(p);
    if (b->type == 7 && b->length == 4) return LoadBytes<float>(p);
    if (b->type == 8 && b->length == 8) return LoadBytes<double>(p);
    FailReading(name_, "block '" + block + "' has type " + std::to_string(b->type) + " and " +
                           std::to_string(b->length) + " bytes, not a number; " + kOpdReexport);
  }

 private:
  const std::string& bytes_;
  const std::string& name_;
  std::map<std::string, OpdBlock> blocks_;
};

struct OpdArray {
  int cols = 0, rows = 0, size = 0;
  const char* values = nullptr;
};

OpdArray ReadOpdArray(const std::string& bytes, const std::string& name, const OpdBlock& block,
                      const std::string& what) {
  if (block.type != kOpdArrayType || block.length < 6) {
    FailReading(name, "block '" + what + "' is not an array (type " + std::to_string(block.type) + ", " +
                          std::to_string(block.length) + " bytes); " + kOpdReexport);
  }
  const char* p = bytes.data() + block.at;
  OpdArray a;
  a.cols = LoadBytes<std::uint16_t>(p);
  a.rows = LoadBytes<std::uint16_t>(p + 2);
  a.size = LoadBytes<std::uint16_t>(p + 4);
  a.values = p + 6;
  const std::uint64_t needed =
      static_cast<std::uint64_t>(a.cols) * static_cast<std::uint64_t>(a.rows) * static_cast<std::uint64_t>(a.size);
  if (a.cols < 1 || a.rows < 1 || needed != block.length - 6) {
    FailReading(name, "block '" + what + "' says " + std::to_string(a.cols) + " x " + std::to_string(a.rows) +
                          " values of " + std::to_string(a.size) + " bytes but holds " +
                          std::to_string(block.length - 6) + " bytes; " + kOpdReexport);
  }
  return a;
}

// The array's value at grid point (ix, iy), iy = 0 the top row: columns are stored bottom row first.
std::size_t OpdArrayIndex(const OpdArray& a, int ix, int iy) {
  return static_cast<std::size_t>(ix) * static_cast<std::size_t>(a.rows) + static_cast<std::size_t>(a.rows - 1 - iy);
}

}  // namespace

bool HasWykoOpdDirectory(const std::string& head) {
  return head.size() >= kOpdDirectoryAt + 10 &&
         std::string_view(head).substr(kOpdDirectoryAt, 10) == std::string_view("Directory\0", 10);
}

HeightMap ParseWykoOpd(const std::string& bytes, const std::string& name) {
  const OpdBlocks blocks(bytes, name);
  // The heights' block is RAW_DATA in the files here; Vision has also named it "RAW DATA", "OPD" and "Raw"
  // (Pastewka's SurfaceTopography, 2021, OPDReader, reads all four).
  const OpdBlock* raw = nullptr;
  std::string raw_name;
  for (const char* candidate : {"RAW_DATA", "RAW DATA", "OPD", "Raw"}) {
    if ((raw = blocks.Find(candidate)) != nullptr) {
      raw_name = candidate;
      break;
    }
  }
  if (!raw) {
    FailReading(name, "has no RAW_DATA block (nor RAW DATA, OPD or Raw): the file holds no heights; save the "
                      "measurement again");
  }
  const OpdArray heights = ReadOpdArray(bytes, name, *raw, raw_name);
  if (heights.size != 2 && heights.size != 4) {
    FailReading(name, "RAW_DATA holds values of " + std::to_string(heights.size) +
                          " bytes; fvm reads int16 (2) and float32 (4) heights");
  }
  const std::optional<double> wavelength_nm = blocks.Number("Wavelength");
  if (!wavelength_nm || !(*wavelength_nm > 0.0) || !std::isfinite(*wavelength_nm)) {
    FailReading(name, "has no positive Wavelength block, the height scale; " + std::string(kOpdReexport));
  }
  // Mult, a positive multiplier, is a 2-byte block read unsigned (values above 32767 occur: SurfaceTopography reads
  // it as uint16 too).
  const double mult = blocks.Number("Mult", /*unsigned_short=*/true).value_or(1.0);
  if (!(mult > 0.0) || !std::isfinite(mult))
    FailReading(name, "block Mult is " + FormatShortest(mult) + ", not positive");
  const std::optional<double> pixel_mm = blocks.Number("Pixel_size");
  const double aspect = blocks.Number("Aspect").value_or(1.0);
  if (!pixel_mm || !(*pixel_mm > 0.0) || !std::isfinite(*pixel_mm) || !(aspect > 0.0) || !std::isfinite(aspect)) {
    FailReading(name, "has no positive Pixel_size and Aspect blocks: the file does not say how large its pixels are");
  }

  HeightMap map;
  map.size_x = heights.cols;
  map.size_y = heights.rows;
  // Float32 as the file holds them, then in double: the pixel Gwyddion reports.
  map.dx_mm = static_cast<double>(static_cast<float>(*pixel_mm));
  map.dy_mm = map.dx_mm * static_cast<double>(static_cast<float>(aspect));
  map.source = "Wyko OPD";
  const double mm_per_count = *wavelength_nm / mult * 1e-6;  // nm to mm
  const std::size_t n = static_cast<std::size_t>(heights.cols) * static_cast<std::size_t>(heights.rows);
  map.z_mm.resize(n);
  for (int iy = 0; iy < heights.rows; ++iy) {
    for (int ix = 0; ix < heights.cols; ++ix) {
      const std::size_t k = OpdArrayIndex(heights, ix, iy);
      double z = std::numeric_limits<double>::quiet_NaN();
      if (heights.size == 2) {
        const std::int16_t v = LoadBytes<std::int16_t>(heights.values + 2 * k);
        if (v != kOpdInvalidInt16) z = mm_per_count * v;
      } else {
        const float v = LoadBytes<float>(heights.values + 4 * k);
        if (std::isfinite(v) && std::fabs(v) < kOpdInvalidFloat) z = mm_per_count * v;
      }
      map.at(ix, iy) = z;
    }
  }
  if (const OpdBlock* image = blocks.Find("Image")) {
    const OpdArray intensity = ReadOpdArray(bytes, name, *image, "Image");
    if (intensity.cols == heights.cols && intensity.rows == heights.rows &&
        (intensity.size == 1 || intensity.size == 2)) {
      map.intensity.resize(n);
      for (int iy = 0; iy < heights.rows; ++iy) {
        for (int ix = 0; ix < heights.cols; ++ix) {
          const std::size_t k = OpdArrayIndex(intensity, ix, iy);
          map.intensity[static_cast<std::size_t>(iy) * heights.cols + ix] =
              intensity.size == 1 ? static_cast<float>(static_cast<unsigned char>(intensity.values[k]))
                                  : static_cast<float>(LoadBytes<std::uint16_t>(intensity.values + 2 * k));
        }
      }
    } else {
      map.notes.push_back("its Image block (" + std::to_string(intensity.cols) + " x " +
                          std::to_string(intensity.rows) + ") is not on the heights' grid; it is not attached to them");
    }
  }
  return map;
}

HeightMap ReadWykoOpd(const std::filesystem::path& path) { return ParseWykoOpd(ReadFileBytes(path), path.string()); }

}  // namespace fvm::imaging
