#include "imaging/io/nms_file.h"

#include <bit>
#include <cmath>
#include <cstdint>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "NMS is little-endian and is copied as it is");

constexpr std::size_t kNmsHeaderSize = 3468;
constexpr const char* kNmsReexport = "the file is damaged or incomplete: export it from the instrument again";

}  // namespace

HeightMap ParseNms(const std::string& bytes, const std::string& name) {
  if (bytes.size() < kNmsHeaderSize) {
    FailReading(name, "holds " + std::to_string(bytes.size()) + " bytes, fewer than the " +
                          std::to_string(kNmsHeaderSize) + " of an NMS header; " + kNmsReexport);
  }
  const char* p = bytes.data();
  const std::int32_t header_size = LoadBytes<std::int32_t>(p + 1352);
  const std::int32_t bytes_per_height = LoadBytes<std::int32_t>(p + 1356);
  if (header_size != static_cast<std::int32_t>(kNmsHeaderSize) || bytes_per_height != 2) {
    FailReading(name, "its header size and bytes per height (at bytes 1352 and 1356) are " +
                          std::to_string(header_size) + " and " + std::to_string(bytes_per_height) +
                          ", not the 3468 and 2 of an NMS height image: not an NMS file fvm reads");
  }
  const std::int64_t count_low = LoadBytes<std::int32_t>(p + 8);
  const std::int64_t count_high = LoadBytes<std::int32_t>(p + 12);
  const double z_low_um = LoadBytes<double>(p + 16);
  const double z_high_um = LoadBytes<double>(p + 24);
  const std::uint64_t cols = LoadBytes<std::uint32_t>(p + 1368);
  const std::uint64_t rows = LoadBytes<std::uint32_t>(p + 1372);
  const double dx_nm = LoadBytes<double>(p + 1376);
  const double dy_nm = LoadBytes<double>(p + 1384);
  RequireGridSize(name, "says", cols, rows, kNmsReexport);
  const std::uint64_t n = cols * rows;
  if (bytes.size() - kNmsHeaderSize < 2 * n) {
    FailReading(name, std::to_string(cols) + " x " + std::to_string(rows) + " heights need " + std::to_string(2 * n) +
                          " bytes after the header, but " + std::to_string(bytes.size() - kNmsHeaderSize) +
                          " follow; " + kNmsReexport);
  }
  if (count_low < 0 || count_high > 65535 || count_high <= count_low) {
    FailReading(name, "the count range at bytes 8 and 12 (" + std::to_string(count_low) + " .. " +
                          std::to_string(count_high) + ") is not an increasing range of uint16; " + kNmsReexport);
  }
  if (!std::isfinite(z_low_um) || !std::isfinite(z_high_um) || !(z_high_um >= z_low_um) || !(dx_nm > 0.0) ||
      !(dy_nm > 0.0) || !std::isfinite(dx_nm) || !std::isfinite(dy_nm)) {
    FailReading(name, "the height range (" + FormatShortest(z_low_um) + " .. " + FormatShortest(z_high_um) +
                          " um) or the pixel sizes (" + FormatShortest(dx_nm) + ", " + FormatShortest(dy_nm) +
                          " nm) are not usable numbers; " + kNmsReexport);
  }

  HeightMap map;
  map.size_x = static_cast<int>(cols);
  map.size_y = static_cast<int>(rows);
  map.dx_mm = dx_nm * 1e-6;
  map.dy_mm = dy_nm * 1e-6;
  map.source = "NMS height image" + std::string(FixedText(p + 32, 20).empty() ? "" : ", " + FixedText(p + 32, 20));
  const double um_per_count = (z_high_um - z_low_um) / static_cast<double>(count_high - count_low);
  map.z_mm.resize(n);
  const char* counts = p + kNmsHeaderSize;
  for (std::size_t i = 0; i < n; ++i) {
    const double count = LoadBytes<std::uint16_t>(counts + 2 * i);
    map.z_mm[i] = (z_low_um + (count - static_cast<double>(count_low)) * um_per_count) / kMmPerMetre;
  }
  if (bytes.size() - kNmsHeaderSize - 2 * n >= n) {
    map.intensity.resize(n);
    const char* grey = counts + 2 * n;
    for (std::size_t i = 0; i < n; ++i) map.intensity[i] = static_cast<unsigned char>(grey[i]);
  }
  return map;
}

HeightMap ReadNms(const std::filesystem::path& path) { return ParseNms(ReadFileBytes(path), path.string()); }

}  // namespace fvm::imaging
