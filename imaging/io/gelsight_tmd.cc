#include "imaging/io/gelsight_tmd.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "TMD is little-endian and is copied as it is");

constexpr std::string_view kTmdSignature("Binary TrueMap Data File v2.0\r\n\0", 32);
constexpr std::string_view kTmdFamily("Binary TrueMap Data File");
constexpr std::size_t kTmdLongestComment = 4096;
constexpr const char* kTmdReexport = "the file is damaged or incomplete: export it from GelSight again";
constexpr std::size_t kTmdHeaderSize = 24;      // columns, rows, lengths and offsets
constexpr std::size_t kTmdFixedCommentSize = 24;

// Where the header starts and how long the comment before it is.
struct TmdLayout {
  std::size_t header_at = 0;
  std::size_t comment_size = 0;
};

// True when a header at `header_at` describes a grid whose float32 heights fill the rest of the file exactly.
bool TmdHeaderFits(const std::string& bytes, std::size_t header_at) {
  if (header_at > bytes.size() || bytes.size() - header_at < kTmdHeaderSize) return false;
  const std::uint64_t cols = LoadBytes<std::uint32_t>(bytes.data() + header_at);
  const std::uint64_t rows = LoadBytes<std::uint32_t>(bytes.data() + header_at + 4);
  return cols >= 1 && rows >= 1 && cols * rows <= kMaxPoints &&
         bytes.size() - header_at - kTmdHeaderSize == 4 * cols * rows;
}

// The comment after the signature is a NUL-ended string (GelSight's description, and the files here); Pastewka's
// SurfaceTopography (2024, TMDReader) reads it as a field of 24 bytes instead. A file laid out either way is read:
// the NUL-ended layout when its header fits the file's size, else the 24-byte field when that one fits; a file that
// fits neither is refused with the NUL-ended layout's numbers.
TmdLayout FindTmdLayout(const std::string& bytes, const std::string& name) {
  const std::string_view view(bytes);
  const std::size_t comment_end = view.find('\0', kTmdSignature.size());
  if (comment_end == std::string_view::npos || comment_end - kTmdSignature.size() > kTmdLongestComment) {
    FailReading(name, "its comment is not ended by a NUL within " + std::to_string(kTmdLongestComment) + " bytes; " +
                          kTmdReexport);
  }
  const TmdLayout ended{comment_end + 1, comment_end - kTmdSignature.size()};
  const TmdLayout fixed{kTmdSignature.size() + kTmdFixedCommentSize,
                        std::min(comment_end - kTmdSignature.size(), kTmdFixedCommentSize)};
  if (!TmdHeaderFits(bytes, ended.header_at) && TmdHeaderFits(bytes, fixed.header_at)) {
    return fixed;
  }
  if (bytes.size() - ended.header_at < kTmdHeaderSize) {
    FailReading(name, "the header (columns, rows, lengths, offsets) is cut short; " + std::string(kTmdReexport));
  }
  const std::uint64_t cols = LoadBytes<std::uint32_t>(bytes.data() + ended.header_at);
  const std::uint64_t rows = LoadBytes<std::uint32_t>(bytes.data() + ended.header_at + 4);
  RequireGridSize(name, "says", cols, rows, kTmdReexport);
  if (bytes.size() - ended.header_at - kTmdHeaderSize != 4 * cols * rows) {
    FailReading(name, std::to_string(cols) + " x " + std::to_string(rows) + " float32 heights need " +
                          std::to_string(4 * cols * rows) + " bytes after the header, but " +
                          std::to_string(bytes.size() - ended.header_at - kTmdHeaderSize) + " follow; " +
                          kTmdReexport);
  }
  return ended;
}

}  // namespace

HeightMap ParseGelSightTmd(const std::string& bytes, const std::string& name) {
  const std::string_view view(bytes);
  if (view.substr(0, kTmdFamily.size()) != kTmdFamily) {
    FailReading(name, "does not start with 'Binary TrueMap Data File': not a GelSight TMD file");
  }
  if (view.substr(0, kTmdSignature.size()) != kTmdSignature) {
    FailReading(name, "is a TMD of another version than v2.0 ('" +
                          QuotedForMessage(FixedText(bytes.data(), std::min<std::size_t>(bytes.size(), 31))) +
                          "'); fvm reads v2.0");
  }
  const TmdLayout layout = FindTmdLayout(bytes, name);
  const char* p = bytes.data() + layout.header_at;
  const std::uint64_t cols = LoadBytes<std::uint32_t>(p);
  const std::uint64_t rows = LoadBytes<std::uint32_t>(p + 4);
  const float length_x = LoadBytes<float>(p + 8);
  const float length_y = LoadBytes<float>(p + 12);
  const float offset_x = LoadBytes<float>(p + 16);
  const float offset_y = LoadBytes<float>(p + 20);
  const std::uint64_t n = cols * rows;
  const std::size_t data_at = layout.header_at + kTmdHeaderSize;
  if (!(length_x > 0.0f) || !(length_y > 0.0f) || !std::isfinite(length_x) || !std::isfinite(length_y) ||
      !std::isfinite(offset_x) || !std::isfinite(offset_y)) {
    FailReading(name, "the lengths (" + FormatShortest(length_x) + ", " + FormatShortest(length_y) +
                          " mm) are not positive or the offsets not finite; " + kTmdReexport);
  }
  HeightMap map;
  map.size_x = static_cast<int>(cols);
  map.size_y = static_cast<int>(rows);
  map.dx_mm = static_cast<double>(length_x) / static_cast<double>(cols);
  map.dy_mm = static_cast<double>(length_y) / static_cast<double>(rows);
  map.x0_mm = offset_x;
  map.y0_mm = offset_y;
  const std::string comment = FixedText(bytes.data() + kTmdSignature.size(), layout.comment_size);
  map.source = "GelSight TMD v2.0" + (comment.empty() ? std::string() : ", " + comment);
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float z = LoadBytes<float>(bytes.data() + data_at + 4 * i);
    map.z_mm[i] = std::isfinite(z) ? static_cast<double>(z) : std::numeric_limits<double>::quiet_NaN();
  }
  return map;
}

HeightMap ReadGelSightTmd(const std::filesystem::path& path) {
  return ParseGelSightTmd(ReadFileBytes(path), path.string());
}

std::string BuildGelSightTmd(const HeightMap& map) {
  if (map.size_x < 1 || map.size_y < 1 ||
      map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y) ||
      !(map.dx_mm > 0.0) || !(map.dy_mm > 0.0)) {
    throw std::invalid_argument("TMD writer: the height map is malformed (sizes, spacing or point count)");
  }
  std::string bytes(kTmdSignature);
  bytes += '\0';  // an empty comment
  AppendBytes(bytes, static_cast<std::uint32_t>(map.size_x));
  AppendBytes(bytes, static_cast<std::uint32_t>(map.size_y));
  AppendBytes(bytes, static_cast<float>(map.dx_mm * map.size_x));
  AppendBytes(bytes, static_cast<float>(map.dy_mm * map.size_y));
  AppendBytes(bytes, static_cast<float>(map.x0_mm));
  AppendBytes(bytes, static_cast<float>(map.y0_mm));
  for (const double z : map.z_mm) AppendBytes(bytes, static_cast<float>(z));
  return bytes;
}

}  // namespace fvm::imaging
