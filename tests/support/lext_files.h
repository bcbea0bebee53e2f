#pragma once
// Olympus LEXT files as an OLS4000 writes them, for the LEXT reader's tests and the fuzzer's seed (test-only: fvm
// writes no LEXT; the layout is the one imaging/io/olympus_lext.h documents). A little-endian multi-page TIFF laid
// out byte by byte here, independently of OpenImageIO, uncompressed, one strip per page:
//   page 0: 8-bit RGB colour (grey), its ImageDescription the <TiffTagDescData> XML with the pixel (0.125 um x
//     0.25 um) and the height per count (1 nm) in picometres;
//   INTENSITY: uint16 grey levels (GreyOf); HEIGHT: uint32 counts of 1 nm from the map's lowest point; INVALID:
//     one bit per point, set where the map's point is invalid (those points' counts are 0).

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "imaging/height_map.h"
#include "tests/support/instrument_files.h"

namespace fvm::imaging::testing {

inline constexpr double kLextDxMm = 0.000125, kLextDyMm = 0.00025, kLextStepMm = 1e-6;

namespace lext_detail {

struct Page {
  std::uint32_t width = 0, height = 0;
  std::uint16_t samples = 1, bits = 8, photometric = 1;
  std::string description;
  std::string pixels;
};

// The TIFF: header, then per page its pixels, description, bits-per-sample array and IFD; each IFD links the next.
inline std::string BuildTiff(const std::vector<Page>& pages) {
  std::string b = std::string("II*\0", 4);
  PutLe<std::uint32_t>(b, 4, 0u);
  std::size_t link = 4;  // where the offset of the next IFD goes
  for (const Page& page : pages) {
    const std::size_t pixels_at = b.size();
    b += page.pixels;
    const std::size_t text_at = b.size();
    b += page.description;
    b += '\0';
    if (b.size() % 2) b += '\0';
    const std::size_t bits_at = b.size();
    for (int s = 0; s < page.samples; ++s) PutLe<std::uint16_t>(b, b.size(), page.bits);
    if (b.size() % 2) b += '\0';
    const std::size_t ifd_at = b.size();
    PutLe<std::uint32_t>(b, link, static_cast<std::uint32_t>(ifd_at));
    struct Entry {
      std::uint16_t tag, type;
      std::uint32_t count, value;
    };
    const std::uint32_t bits_value = page.samples == 1 ? page.bits : static_cast<std::uint32_t>(bits_at);
    const std::vector<Entry> entries = {
        {256, 4, 1, page.width},
        {257, 4, 1, page.height},
        {258, 3, page.samples, bits_value},
        {259, 3, 1, 1},
        {262, 3, 1, page.photometric},
        {270, 2, static_cast<std::uint32_t>(page.description.size() + 1), static_cast<std::uint32_t>(text_at)},
        {273, 4, 1, static_cast<std::uint32_t>(pixels_at)},
        {277, 3, 1, page.samples},
        {278, 4, 1, page.height},
        {279, 4, 1, static_cast<std::uint32_t>(page.pixels.size())},
        {284, 3, 1, 1}};
    PutLe<std::uint16_t>(b, ifd_at, static_cast<std::uint16_t>(entries.size()));
    std::size_t at = ifd_at + 2;
    for (const Entry& e : entries) {
      PutLe<std::uint16_t>(b, at, e.tag);
      PutLe<std::uint16_t>(b, at + 2, e.type);
      PutLe<std::uint32_t>(b, at + 4, e.count);
      if (e.type == 3 && e.count == 1) {
        PutLe<std::uint16_t>(b, at + 8, static_cast<std::uint16_t>(e.value));
        PutLe<std::uint16_t>(b, at + 10, 0);
      } else {
        PutLe<std::uint32_t>(b, at + 8, e.value);
      }
      at += 12;
    }
    link = at;
    PutLe<std::uint32_t>(b, link, 0u);
  }
  return b;
}

}  // namespace lext_detail

inline std::string BuildLext(const HeightMap& map) {
  using lext_detail::Page;
  const std::uint32_t w = static_cast<std::uint32_t>(map.size_x), h = static_cast<std::uint32_t>(map.size_y);
  const std::size_t n = map.z_mm.size();
  Page colour{w, h, 3, 8, 2,
              "<?xml version=\"1.0\" encoding=\"UTF-8\"?><TiffTagDescData version=\"1.0\"><HeightInfo>"
              "<HeightDataPerPixelX>125000</HeightDataPerPixelX><HeightDataPerPixelY>250000</HeightDataPerPixelY>"
              "<HeightDataPerPixelZ>1000</HeightDataPerPixelZ><HeightDataUnit>pm</HeightDataUnit></HeightInfo>"
              "<IntensityInfo><IntensityDataPerPixelX>125000</IntensityDataPerPixelX><IntensityDataPerPixelY>"
              "250000</IntensityDataPerPixelY><IntensityDataPerPixelZ>1</IntensityDataPerPixelZ></IntensityInfo>"
              "</TiffTagDescData>",
              {}};
  for (std::size_t i = 0; i < n; ++i) colour.pixels += std::string(3, static_cast<char>(GreyOf(i)));
  Page intensity{w, h, 1, 16, 1, "INTENSITY", {}};
  for (std::size_t i = 0; i < n; ++i) PutLe<std::uint16_t>(intensity.pixels, 2 * i, GreyOf(i));
  double lowest = INFINITY;
  for (const double z : map.z_mm) lowest = std::isfinite(z) ? std::min(lowest, z) : lowest;
  Page height{w, h, 1, 32, 1, "HEIGHT", {}};
  for (std::size_t i = 0; i < n; ++i) {
    const double z = map.z_mm[i];
    PutLe<std::uint32_t>(height.pixels, 4 * i,
                         static_cast<std::uint32_t>(std::isfinite(z) ? std::round((z - lowest) / kLextStepMm) : 0.0));
  }
  Page invalid{w, h, 1, 1, 1, "INVALID", {}};
  const std::size_t row_bytes = (w + 7) / 8;
  invalid.pixels.assign(row_bytes * h, '\0');
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      if (!std::isfinite(map.z_mm[y * w + x])) invalid.pixels[y * row_bytes + x / 8] |= static_cast<char>(0x80 >> (x % 8));
    }
  }
  return lext_detail::BuildTiff({colour, intensity, height, invalid});
}

}  // namespace fvm::imaging::testing
