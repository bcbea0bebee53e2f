#pragma once
// Small files in the layouts of other instruments' exports, written the way the instruments write them (the
// layouts their readers document: imaging/io/sensofar_plu.h, metropro_dat.h, wyko_opd.h, digital_surf_sur.h,
// nms_file.h, keyence_vk4.h; gelsight_tmd.h has its own writer), for the readers' tests and the fuzzers' seeds. Test-only: fvm
// writes none of these formats. Heights are quantised as the instruments quantise them (counts of a step); each
// builder says its step so that a test can hold a read-back to half of it.

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "imaging/height_map.h"
#include "imaging/io/zip_archive.h"

namespace fvm::imaging::testing {

// Bytes at a position of a buffer, little- or big-endian.
template <typename T>
void PutLe(std::string& bytes, std::size_t at, T value) {
  if (bytes.size() < at + sizeof(T)) bytes.resize(at + sizeof(T), '\0');
  std::memcpy(bytes.data() + at, &value, sizeof value);
}
template <typename T>
void PutBe(std::string& bytes, std::size_t at, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof value);
  if (bytes.size() < at + sizeof(T)) bytes.resize(at + sizeof(T), '\0');
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes[at + i] = raw[sizeof(T) - 1 - i];
}
inline void PutText(std::string& bytes, std::size_t at, std::string_view text) {
  if (bytes.size() < at + text.size()) bytes.resize(at + text.size(), '\0');
  std::memcpy(bytes.data() + at, text.data(), text.size());
}

// An 8-bit grey level per point, for the intensity images.
inline unsigned char GreyOf(std::size_t i) { return static_cast<unsigned char>((37 * i + 11) % 251); }

// Sensofar PLU, topography (type 3) with the S neox colour image after the heights. Heights as float32 um.
// `layers` > 1 writes a multi-layer measurement: after the surface, layers of the same grid 5 um lower each, then
// the colour image.
inline std::string BuildPlu(const HeightMap& map, int layers = 1) {
  std::string b(500, '\0');
  PutText(b, 0, "Mon Apr 19 11:40:13 2021");
  PutLe<std::uint32_t>(b, 128, 1618832413u);
  PutText(b, 132, "written by fvm's tests");
  PutLe<std::uint32_t>(b, 388, static_cast<std::uint32_t>(map.size_y));
  PutLe<std::uint32_t>(b, 392, static_cast<std::uint32_t>(map.size_x));
  PutLe<std::uint32_t>(b, 396, static_cast<std::uint32_t>(map.size_x));
  PutLe<float>(b, 400, 1.0f);
  PutLe<float>(b, 404, static_cast<float>(map.dx_mm * 1000.0));
  PutLe<float>(b, 408, static_cast<float>(map.dy_mm * 1000.0));
  PutLe<std::uint32_t>(b, 428, 3u);  // topography
  PutLe<std::uint32_t>(b, 456, static_cast<std::uint32_t>(map.size_y));
  PutLe<std::uint32_t>(b, 460, static_cast<std::uint32_t>(map.size_x));
  b[489] = static_cast<char>(layers);  // num_layers
  std::size_t at = 500;
  for (int layer = 0; layer < layers; ++layer) {
    PutLe<std::uint32_t>(b, at, static_cast<std::uint32_t>(map.size_y));
    PutLe<std::uint32_t>(b, at + 4, static_cast<std::uint32_t>(map.size_x));
    at += 8;
    for (const double z : map.z_mm) {
      PutLe<float>(b, at, std::isfinite(z) ? static_cast<float>(z * 1000.0 - 5.0 * layer) : 1000001.0f);
      at += 4;
    }
    PutLe<float>(b, at, 1000001.0f);
    PutLe<float>(b, at + 4, 1000001.0f);
    at += 8;
  }
  for (std::size_t i = 0; i < map.z_mm.size(); ++i, at += 3)
    PutText(b, at, std::string(3, static_cast<char>(GreyOf(i))));
  return b;
}

// Zygo MetroPro DAT, header format 1, phase_res 1: a count is 0.5 x 632.8 nm / 32768 (about 9.66 pm).
inline double MetroProStepMm() { return 0.5 * static_cast<double>(632.8e-9f) / 32768.0 * 1000.0; }
inline std::string BuildMetroPro(const HeightMap& map) {
  const std::size_t n = map.z_mm.size();
  std::string b(834, '\0');
  PutBe<std::uint32_t>(b, 0, 0x881B036Fu);
  PutBe<std::uint16_t>(b, 4, 1);
  PutBe<std::uint32_t>(b, 6, 834u);
  PutBe<std::uint16_t>(b, 52, static_cast<std::uint16_t>(map.size_x));
  PutBe<std::uint16_t>(b, 54, static_cast<std::uint16_t>(map.size_y));
  PutBe<std::uint16_t>(b, 56, 1);
  PutBe<std::int16_t>(b, 58, 255);
  PutBe<std::uint32_t>(b, 60, static_cast<std::uint32_t>(2 * n));
  PutBe<std::uint16_t>(b, 68, static_cast<std::uint16_t>(map.size_x));
  PutBe<std::uint16_t>(b, 70, static_cast<std::uint16_t>(map.size_y));
  PutBe<std::uint32_t>(b, 72, static_cast<std::uint32_t>(4 * n));
  PutBe<float>(b, 164, 0.5f);
  PutBe<float>(b, 168, 632.8e-9f);
  PutBe<float>(b, 176, 1.0f);
  PutBe<float>(b, 184, static_cast<float>(map.dx_mm / 1000.0));
  PutBe<std::int16_t>(b, 218, 1);
  const double step_mm = MetroProStepMm();
  for (std::size_t i = 0; i < n; ++i) PutBe<std::uint16_t>(b, 834 + 2 * i, GreyOf(i));
  for (std::size_t i = 0; i < n; ++i) {
    const double z = map.z_mm[i];
    PutBe<std::int32_t>(b, 834 + 2 * n + 4 * i,
                        std::isfinite(z) ? static_cast<std::int32_t>(std::lround(z / step_mm)) : 2147483647);
  }
  return b;
}

// Wyko OPD: int16 counts of 632.8 nm / 64 (about 9.9 nm), columns stored bottom row first, and an Image block.
inline double OpdStepMm() { return static_cast<double>(632.8f) / 64.0 * 1e-6; }
// `heights_block` names the heights' array ("RAW_DATA" in the files here; SurfaceTopography also knows "RAW DATA",
// "OPD" and "Raw"); `mult` is the height divisor, a 2-byte block read unsigned.
inline std::string BuildOpd(const HeightMap& map, const std::string& heights_block = "RAW_DATA",
                            std::uint16_t mult = 64) {
  struct Entry {
    std::string name;
    std::int16_t type;
    std::string data;
  };
  const auto number = [](auto value) {
    std::string d;
    PutLe(d, 0, value);
    return d;
  };
  const auto array = [&](int element, auto value_at) {
    std::string d;
    PutLe<std::uint16_t>(d, 0, static_cast<std::uint16_t>(map.size_x));
    PutLe<std::uint16_t>(d, 2, static_cast<std::uint16_t>(map.size_y));
    PutLe<std::uint16_t>(d, 4, static_cast<std::uint16_t>(element));
    std::size_t at = 6;
    for (int ix = 0; ix < map.size_x; ++ix) {
      for (int iy = map.size_y - 1; iy >= 0; --iy, at += element) value_at(d, at, ix, iy);
    }
    return d;
  };
  const float wavelength = 632.8f;
  const double step_nm = static_cast<double>(wavelength) / mult;
  std::vector<Entry> entries = {
      {heights_block, 3,
       array(2,
             [&](std::string& d, std::size_t at, int ix, int iy) {
               const double z = map.at(ix, iy);
               PutLe<std::int16_t>(
                   d, at, std::isfinite(z) ? static_cast<std::int16_t>(std::lround(z * 1e6 / step_nm)) : 32767);
             })},
      {"Image", 3,
       array(1, [&](std::string& d, std::size_t at, int ix,
                    int iy) { PutLe<unsigned char>(d, at, GreyOf(static_cast<std::size_t>(iy) * map.size_x + ix)); })},
      {"Wavelength", 7, number(wavelength)},
      {"Mult", 6, number(mult)},
      {"Pixel_size", 7, number(static_cast<float>(map.dx_mm))},
      {"Aspect", 7, number(static_cast<float>(map.dy_mm / map.dx_mm))},
  };
  const std::size_t directory = 24 * (entries.size() + 1);
  std::string b(2 + directory, '\0');
  PutLe<std::uint16_t>(b, 0, 1);
  const auto put_entry = [&](std::size_t at, const std::string& name, std::int16_t type, std::size_t length) {
    PutText(b, at, name);
    PutLe<std::int16_t>(b, at + 16, type);
    PutLe<std::int32_t>(b, at + 18, static_cast<std::int32_t>(length));
    PutLe<std::uint16_t>(b, at + 22, 0xFFFF);
  };
  put_entry(2, "Directory", 1, directory);
  for (std::size_t e = 0; e < entries.size(); ++e) {
    put_entry(2 + 24 * (e + 1), entries[e].name, entries[e].type, entries[e].data.size());
  }
  for (const Entry& e : entries) b += e.data;
  return b;
}

// Digital Surf SUR, an int32 surface with the non-measured flag; compressed: one zlib stream ("DSCOMPRESSED").
// Counts of 1e-4 um (0.1 nm), float32 as the header holds them.
inline double SurStepMm() { return static_cast<double>(1e-4f) / 1000.0; }
inline std::string BuildSur(const HeightMap& map, bool compressed = false) {
  const std::size_t n = map.z_mm.size();
  constexpr std::int32_t kMin = -2000000000;
  std::string b(512, ' ');
  PutText(b, 0, compressed ? "DSCOMPRESSED" : "DIGITAL SURF");
  PutLe<std::int16_t>(b, 12, 0);
  PutLe<std::int16_t>(b, 14, 1);
  PutLe<std::int16_t>(b, 16, 1);
  PutLe<std::int16_t>(b, 18, 2);
  PutText(b, 20, std::string(30, ' ').replace(0, 6, "sample"));
  for (std::size_t at : {80, 82, 84, 88, 90, 92, 94, 96}) PutLe<std::int16_t>(b, at, 0);
  PutLe<std::int16_t>(b, 86, 1);
  PutLe<std::int16_t>(b, 98, 32);
  PutLe<std::int32_t>(b, 100, kMin);
  PutLe<std::int32_t>(b, 104, 2000000000);
  PutLe<std::int32_t>(b, 108, map.size_x);
  PutLe<std::int32_t>(b, 112, map.size_y);
  PutLe<std::int32_t>(b, 116, static_cast<std::int32_t>(n));
  PutLe<float>(b, 120, static_cast<float>(map.dx_mm * 1000.0));
  PutLe<float>(b, 124, static_cast<float>(map.dy_mm * 1000.0));
  PutLe<float>(b, 128, 1e-4f);
  for (std::size_t at = 180; at < 276; at += 16) PutText(b, at, std::string(16, ' ').replace(0, 2, "um"));
  for (std::size_t at : {276, 280, 284}) PutLe<float>(b, at, 1.0f);
  for (std::size_t at = 288; at < 338; at += 2) PutLe<std::int16_t>(b, at, 0);
  PutLe<float>(b, 474, 0.0f);
  std::string data;
  const double step_mm = SurStepMm();
  for (std::size_t i = 0; i < n; ++i) {
    const double z = map.z_mm[i];
    PutLe<std::int32_t>(data, 4 * i, std::isfinite(z) ? static_cast<std::int32_t>(std::lround(z / step_mm)) : kMin - 2);
  }
  if (!compressed) return b + data;
  uLongf zipped_size = compressBound(static_cast<uLong>(data.size()));
  std::string zipped(zipped_size, '\0');
  compress(reinterpret_cast<Bytef*>(zipped.data()), &zipped_size, reinterpret_cast<const Bytef*>(data.data()),
           static_cast<uLong>(data.size()));
  zipped.resize(zipped_size);
  std::string block;
  PutLe<std::uint32_t>(block, 0, 1u);
  PutLe<std::uint32_t>(block, 4, static_cast<std::uint32_t>(data.size()));
  PutLe<std::uint32_t>(block, 8, static_cast<std::uint32_t>(zipped.size()));
  block += zipped;
  PutLe<std::uint32_t>(b, 324, static_cast<std::uint32_t>(block.size()));
  return b + block;
}

// Sensofar PLUx: index.xml with the grid and the pixel sizes (FOV_X, FOV_Y, micrometres), LAYER_0.raw with float32
// micrometres (NaN where not measured).
inline std::string BuildPlux(const HeightMap& map) {
  const std::string index =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<xml>\n  <GENERAL>\n    <IMAGE_SIZE_X>" +
      std::to_string(map.size_x) + "</IMAGE_SIZE_X>\n    <IMAGE_SIZE_Y>" + std::to_string(map.size_y) +
      "</IMAGE_SIZE_Y>\n    <FOV_X>" + std::to_string(map.dx_mm * 1000.0) + "</FOV_X>\n    <FOV_Y>" +
      std::to_string(map.dy_mm * 1000.0) +
      "</FOV_Y>\n  </GENERAL>\n  <LAYER_0>\n    <FILENAME_Z>LAYER_0.raw</FILENAME_Z>\n  </LAYER_0>\n</xml>\n";
  std::string heights;
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    PutLe<float>(heights, 4 * i, static_cast<float>(map.z_mm[i] * 1000.0));  // NaN stays NaN
  }
  return BuildZip({{"LAYER_0.raw", heights}, {"index.xml", index}});
}

// NMS height image: uint16 counts over the map's height range, then an 8-bit intensity per point.
inline std::string BuildNms(const HeightMap& map, double z_low_um, double z_high_um) {
  const std::size_t n = map.z_mm.size();
  std::string b(3468, '\0');
  PutLe<std::int32_t>(b, 0, 2);
  PutLe<std::int32_t>(b, 4, 1);
  PutLe<std::int32_t>(b, 8, 0);
  PutLe<std::int32_t>(b, 12, 65535);
  PutLe<double>(b, 16, z_low_um);
  PutLe<double>(b, 24, z_high_um);
  PutText(b, 32, "OM_MS_2.0");
  PutText(b, 52, "Confocal Height Image");
  PutLe<std::int32_t>(b, 1352, 3468);
  PutLe<std::int32_t>(b, 1356, 2);
  PutLe<std::uint32_t>(b, 1368, static_cast<std::uint32_t>(map.size_x));
  PutLe<std::uint32_t>(b, 1372, static_cast<std::uint32_t>(map.size_y));
  PutLe<double>(b, 1376, map.dx_mm * 1e6);
  PutLe<double>(b, 1384, map.dy_mm * 1e6);
  for (std::size_t i = 0; i < n; ++i) {
    const double z_um = std::isfinite(map.z_mm[i]) ? map.z_mm[i] * 1000.0 : z_low_um;
    const double count = std::round((z_um - z_low_um) / (z_high_um - z_low_um) * 65535.0);
    PutLe<std::uint16_t>(b, 3468 + 2 * i, static_cast<std::uint16_t>(std::clamp(count, 0.0, 65535.0)));
  }
  for (std::size_t i = 0; i < n; ++i) PutLe<unsigned char>(b, 3468 + 2 * n + i, GreyOf(i));
  return b;
}

// Keyence VK4 as a VK-X writes a single measurement: header, offset table, a 304-byte measurement-conditions block
// (pixel 0.5 um x 0.75 um, z 1 nm per digit, stated in picometres), the light image (16-bit, the grey levels) and
// the height image (32-bit counts of 1 nm: heights are counted from the map's lowest point, as the instrument
// counts from the bottom of its scan; invalid points, which VK4 cannot mark, become count 0), then the title and
// the lens name as UTF-16 strings. `map` gives the grid; its dx, dy are ignored.
inline constexpr double kVk4DxMm = 0.0005, kVk4DyMm = 0.00075, kVk4StepMm = 1e-6;
inline std::string BuildVk4(const HeightMap& map) {
  const std::size_t n = map.z_mm.size();
  std::string b;
  PutText(b, 0, "VK4_");
  PutLe<std::uint32_t>(b, 4, 0x01000003u);
  PutLe<std::uint32_t>(b, 8, 0u);
  const std::uint32_t conditions = 84, light = conditions + 304, height = light + 796 + 2 * static_cast<std::uint32_t>(n);
  const std::uint32_t strings = height + 796 + 4 * static_cast<std::uint32_t>(n);
  PutLe<std::uint32_t>(b, 12, conditions);
  PutLe<std::uint32_t>(b, 12 + 4 * 3, light);
  PutLe<std::uint32_t>(b, 12 + 4 * 6, height);
  PutLe<std::uint32_t>(b, 12 + 4 * 16, strings);
  PutLe<std::uint32_t>(b, conditions, 304u);
  PutLe<std::uint32_t>(b, conditions + 4, 2024u);
  PutLe<std::uint32_t>(b, conditions + 168, 500000u);
  PutLe<std::uint32_t>(b, conditions + 172, 750000u);
  PutLe<std::uint32_t>(b, conditions + 176, 1000u);
  const auto image_header = [&](std::uint32_t at, std::uint32_t bits) {
    PutLe<std::uint32_t>(b, at, static_cast<std::uint32_t>(map.size_x));
    PutLe<std::uint32_t>(b, at + 4, static_cast<std::uint32_t>(map.size_y));
    PutLe<std::uint32_t>(b, at + 8, bits);
    PutLe<std::uint32_t>(b, at + 12, 0u);
    PutLe<std::uint32_t>(b, at + 16, static_cast<std::uint32_t>(n * bits / 8));
    PutLe<std::uint32_t>(b, at + 24, bits == 16 ? 65535u : 0xFFFFFFFFu);
  };
  image_header(light, 16);
  for (std::size_t i = 0; i < n; ++i) PutLe<std::uint16_t>(b, light + 796 + 2 * i, GreyOf(i));
  image_header(height, 32);
  double lowest = INFINITY;
  for (const double z : map.z_mm) lowest = std::isfinite(z) ? std::min(lowest, z) : lowest;
  for (std::size_t i = 0; i < n; ++i) {
    const double z = map.z_mm[i];
    const double count = std::isfinite(z) ? std::round((z - lowest) / kVk4StepMm) : 0.0;
    PutLe<std::uint32_t>(b, height + 796 + 4 * i, static_cast<std::uint32_t>(count));
  }
  std::size_t at = strings;
  for (const std::string_view text : {std::string_view("calotte"), std::string_view("50x")}) {
    PutLe<std::uint32_t>(b, at, static_cast<std::uint32_t>(text.size()));
    at += 4;
    for (const char c : text) {
      PutLe<std::uint16_t>(b, at, static_cast<std::uint16_t>(c));
      at += 2;
    }
  }
  return b;
}

}  // namespace fvm::imaging::testing
