#include "imaging/io/metropro_dat.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

constexpr std::uint32_t kMetroProMagicBase = 0x881B036E;  // + header format (1, 2, 3)
constexpr std::int32_t kMetroProInvalidPhase = 2147483640;
constexpr std::uint16_t kMetroProInvalidIntensity = 65412;  // and above: Gwyddion's threshold for an unlit pixel
constexpr const char* kDatReexport = "the file is damaged or incomplete: save it from MetroPro again";

// The header fields fvm uses, by byte offset (MetroPro Reference Guide, "Data file format").
struct DatHeader {
  int format = 0;
  std::uint32_t header_size = 0;
  int ac_org_x = 0, ac_org_y = 0, ac_width = 0, ac_height = 0, ac_buckets = 0;
  std::uint32_t ac_bytes = 0;
  int cn_org_x = 0, cn_org_y = 0, cn_width = 0, cn_height = 0;
  std::uint32_t cn_bytes = 0;
  double scale_factor = 0, wavelength_m = 0, obliquity = 0, lateral_res_m = 0;
  int phase_res = 0;
  bool inverted = false;
};

DatHeader ParseMetroProHeader(const std::string& bytes) {
  const char* p = bytes.data();
  DatHeader h;
  h.format = static_cast<int>(LoadBigEndian<std::uint32_t>(p) - kMetroProMagicBase);
  h.header_size = LoadBigEndian<std::uint32_t>(p + 6);
  h.ac_org_x = LoadBigEndian<std::int16_t>(p + 48);
  h.ac_org_y = LoadBigEndian<std::int16_t>(p + 50);
  h.ac_width = LoadBigEndian<std::uint16_t>(p + 52);
  h.ac_height = LoadBigEndian<std::uint16_t>(p + 54);
  h.ac_buckets = LoadBigEndian<std::uint16_t>(p + 56);
  h.ac_bytes = LoadBigEndian<std::uint32_t>(p + 60);
  h.cn_org_x = LoadBigEndian<std::int16_t>(p + 64);
  h.cn_org_y = LoadBigEndian<std::int16_t>(p + 66);
  h.cn_width = LoadBigEndian<std::uint16_t>(p + 68);
  h.cn_height = LoadBigEndian<std::uint16_t>(p + 70);
  h.cn_bytes = LoadBigEndian<std::uint32_t>(p + 72);
  h.scale_factor = LoadBigEndian<float>(p + 164);
  h.wavelength_m = LoadBigEndian<float>(p + 168);
  h.obliquity = LoadBigEndian<float>(p + 176);
  h.lateral_res_m = LoadBigEndian<float>(p + 184);
  h.phase_res = LoadBigEndian<std::int16_t>(p + 218);
  h.inverted = LoadBigEndian<std::int16_t>(p + 232) != 0;
  return h;
}

}  // namespace

bool HasMetroProMagic(const std::string& head) {
  if (head.size() < 4) return false;
  const std::uint32_t magic = LoadBigEndian<std::uint32_t>(head.data());
  return magic >= kMetroProMagicBase + 1 && magic <= kMetroProMagicBase + 3;
}

HeightMap ParseMetroProDat(const std::string& bytes, const std::string& name) {
  if (!HasMetroProMagic(bytes)) {
    FailReading(name,
                "does not start with the MetroPro magic 0x881B036F, 0x881B0370 or 0x881B0371: not a Zygo "
                "MetroPro DAT file");
  }
  constexpr std::size_t kSmallestHeader = 834;
  if (bytes.size() < kSmallestHeader) {
    FailReading(name, "holds " + std::to_string(bytes.size()) + " bytes, fewer than the 834 of a MetroPro header; " +
                          kDatReexport);
  }
  const DatHeader h = ParseMetroProHeader(bytes);
  const std::uint32_t expected_header = h.format == 3 ? 4096 : 834;
  if (h.header_size != expected_header) {
    FailReading(name, "header_size is " + std::to_string(h.header_size) + " where header format " +
                          std::to_string(h.format) + " has " + std::to_string(expected_header) + "; " + kDatReexport);
  }
  if (h.cn_width < 1 || h.cn_height < 1) {
    FailReading(name, "holds no phase data (cn_width x cn_height is " + std::to_string(h.cn_width) + " x " +
                          std::to_string(h.cn_height) + "): save the measurement with its phase (heights)");
  }
  const std::uint64_t n = static_cast<std::uint64_t>(h.cn_width) * static_cast<std::uint64_t>(h.cn_height);
  const std::uint64_t intensity_bytes = 2ull * static_cast<std::uint64_t>(h.ac_width) *
                                        static_cast<std::uint64_t>(h.ac_height) *
                                        static_cast<std::uint64_t>(h.ac_buckets);
  if (h.ac_bytes != intensity_bytes) {
    FailReading(name, "ac_n_bytes is " + std::to_string(h.ac_bytes) +
                          " but ac_width x ac_height x ac_n_buckets x 2 is " + std::to_string(intensity_bytes) + "; " +
                          kDatReexport);
  }
  if (h.cn_bytes != 4 * n) {
    FailReading(name, "cn_n_bytes is " + std::to_string(h.cn_bytes) + " but cn_width x cn_height x 4 is " +
                          std::to_string(4 * n) + "; " + kDatReexport);
  }
  const std::uint64_t phase_at = h.header_size + intensity_bytes;
  if (bytes.size() < phase_at + 4 * n) {
    FailReading(name, "the header announces " + std::to_string(phase_at + 4 * n) +
                          " bytes (header, intensity, phase) " + "but the file holds " + std::to_string(bytes.size()) +
                          "; " + kDatReexport);
  }
  if (h.phase_res < 0 || h.phase_res > 2) {
    FailReading(name, "phase_res is " + std::to_string(h.phase_res) + ", not 0, 1 or 2; " + kDatReexport);
  }
  if (!(h.lateral_res_m > 0.0) || !std::isfinite(h.lateral_res_m)) {
    FailReading(name, "lateral_res (the pixel size) is " + FormatShortest(h.lateral_res_m) +
                          ": the file does not say how large its pixels are; calibrate the lateral resolution in "
                          "MetroPro and save again");
  }
  const double resolution = h.phase_res == 0 ? 4096.0 : h.phase_res == 1 ? 32768.0 : 131072.0;
  const double metres_per_count =
      (h.inverted ? -1.0 : 1.0) * h.scale_factor * h.obliquity * h.wavelength_m / resolution;
  if (!std::isfinite(metres_per_count) || metres_per_count == 0.0) {
    FailReading(name, "intf_scale_factor x obliquity_factor x wavelength_in (" + FormatShortest(h.scale_factor) +
                          " x " + FormatShortest(h.obliquity) + " x " + FormatShortest(h.wavelength_m) +
                          " m) gives no height scale; " + kDatReexport);
  }

  HeightMap map;
  map.size_x = h.cn_width;
  map.size_y = h.cn_height;
  map.dx_mm = h.lateral_res_m * kMmPerMetre;
  map.dy_mm = map.dx_mm;
  map.source = "Zygo MetroPro DAT, header format " + std::to_string(h.format);
  map.z_mm.resize(n);
  const char* phase = bytes.data() + phase_at;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t count = LoadBigEndian<std::int32_t>(phase + 4 * i);
    map.z_mm[i] = count >= kMetroProInvalidPhase ? std::numeric_limits<double>::quiet_NaN()
                                                 : metres_per_count * static_cast<double>(count) * kMmPerMetre;
  }
  // The intensity image belongs to the heights' grid only where the camera windows coincide.
  if (h.ac_buckets >= 1 && h.ac_width == h.cn_width && h.ac_height == h.cn_height && h.ac_org_x == h.cn_org_x &&
      h.ac_org_y == h.cn_org_y) {
    map.intensity.resize(n);
    const char* counts = bytes.data() + h.header_size;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint16_t v = LoadBigEndian<std::uint16_t>(counts + 2 * i);
      map.intensity[i] =
          v >= kMetroProInvalidIntensity ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v);
    }
  } else if (h.ac_buckets >= 1) {
    map.notes.push_back("its intensity image (" + std::to_string(h.ac_width) + " x " + std::to_string(h.ac_height) +
                        ") covers another camera window than the heights; it is not attached to them");
  }
  return map;
}

HeightMap ReadMetroProDat(const std::filesystem::path& path) {
  return ParseMetroProDat(ReadFileBytes(path), path.string());
}

}  // namespace fvm::imaging
