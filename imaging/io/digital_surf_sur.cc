#include "imaging/io/digital_surf_sur.h"

#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

static_assert(std::endian::native == std::endian::little, "SUR is little-endian and is copied as it is");

constexpr std::size_t kSurHeaderSize = 512;
constexpr int kSurSurface = 2;
constexpr const char* kSurReexport = "the file is damaged or incomplete: save it from MountainsMap again";

// Millimetres per unit of a SUR unit field; nullopt for a unit fvm does not know.
std::optional<double> SurUnitMm(std::string unit) {
  if (unit == "m") return 1000.0;
  if (unit == "mm") return 1.0;
  if (unit == "um" || unit == "\xB5m" || unit == "\xC2\xB5m" || unit == "\xCE\xBCm") return 1e-3;
  if (unit == "nm") return 1e-6;
  if (unit == "pm") return 1e-9;
  if (unit == "A" || unit == "\xC5" || unit == "\xC3\x85") return 1e-7;  // angstrom
  return std::nullopt;
}

double SurUnit(const std::string& name, const char* field, const char* p) {
  const std::string unit = FixedText(p, 16);
  const std::optional<double> mm = SurUnitMm(unit);
  if (!mm) {
    FailReading(name, std::string(field) + " is '" + QuotedForMessage(unit) +
                          "', not a length unit fvm knows (m, mm, um, nm, pm, A)");
  }
  return *mm;
}

// The counts of a DSCOMPRESSED object: zlib streams after their directory, inflated and joined.
std::string InflateSurStreams(const std::string& bytes, std::size_t at, std::uint64_t declared, std::uint64_t wanted,
                              const std::string& name) {
  if (declared < 4 || declared > bytes.size() - at) {
    FailReading(name, "the compressed data size in the header (" + std::to_string(declared) +
                          " bytes) does not fit the file after its header; " + kSurReexport);
  }
  const char* p = bytes.data() + at;
  const std::uint32_t streams = LoadBytes<std::uint32_t>(p);
  if (streams < 1 || 4 + 8 * static_cast<std::uint64_t>(streams) > declared) {
    FailReading(name, "the compressed data's directory says " + std::to_string(streams) + " streams, which its " +
                          std::to_string(declared) + " bytes cannot hold; " + kSurReexport);
  }
  std::string out;
  std::uint64_t zipped_at = 4 + 8 * static_cast<std::uint64_t>(streams);
  for (std::uint32_t s = 0; s < streams; ++s) {
    const std::uint64_t raw = LoadBytes<std::uint32_t>(p + 4 + 8 * s);
    const std::uint64_t zipped = LoadBytes<std::uint32_t>(p + 8 + 8 * s);
    if (zipped > declared - zipped_at || raw > wanted - out.size()) {
      FailReading(name, "compressed stream " + std::to_string(s + 1) + " (" + std::to_string(zipped) + " bytes, " +
                            std::to_string(raw) + " inflated) does not fit the data the header declares; " +
                            kSurReexport);
    }
    const std::size_t start = out.size();
    out.resize(start + raw);
    uLongf inflated = static_cast<uLongf>(raw);
    const int status = uncompress(reinterpret_cast<Bytef*>(out.data() + start), &inflated,
                                  reinterpret_cast<const Bytef*>(p + zipped_at), static_cast<uLong>(zipped));
    if (status != Z_OK || inflated != raw) {
      FailReading(name, "compressed stream " + std::to_string(s + 1) + " does not inflate to its " +
                            std::to_string(raw) + " bytes (zlib status " + std::to_string(status) + "); " +
                            kSurReexport);
    }
    zipped_at += zipped;
  }
  return out;
}

}  // namespace

HeightMap ParseDigitalSurfSur(const std::string& bytes, const std::string& name) {
  const std::string_view signature = std::string_view(bytes).substr(0, 12);
  const bool compressed = signature == "DSCOMPRESSED";
  if (signature != "DIGITAL SURF" && !compressed) {
    FailReading(name, "does not start with 'DIGITAL SURF' or 'DSCOMPRESSED': not a Digital Surf SUR file");
  }
  if (bytes.size() < kSurHeaderSize) {
    FailReading(
        name, "holds " + std::to_string(bytes.size()) + " bytes, fewer than the 512 of a SUR header; " + kSurReexport);
  }
  const char* p = bytes.data();
  const int format = LoadBytes<std::int16_t>(p + 12);
  const int objects = LoadBytes<std::int16_t>(p + 14);
  const int studiable = LoadBytes<std::int16_t>(p + 18);
  const bool non_measured = LoadBytes<std::int16_t>(p + 86) == 1;
  const int bits = LoadBytes<std::int16_t>(p + 98);
  const std::int32_t declared_min = LoadBytes<std::int32_t>(p + 100);
  const std::int64_t per_line = LoadBytes<std::int32_t>(p + 108);
  const std::int64_t lines = LoadBytes<std::int32_t>(p + 112);
  const double dx = std::fabs(LoadBytes<float>(p + 120));
  const double dy = std::fabs(LoadBytes<float>(p + 124));
  const double dz = LoadBytes<float>(p + 128);
  const int inverted = LoadBytes<std::int16_t>(p + 290);
  const std::uint64_t compressed_size = LoadBytes<std::uint32_t>(p + 324);
  const std::size_t comment = LoadBytes<std::uint16_t>(p + 334);
  const std::size_t private_zone = LoadBytes<std::uint16_t>(p + 336);
  const double z_offset = LoadBytes<float>(p + 474);

  if (format != 0) {
    FailReading(name,
                "is in SUR format " + std::to_string(format) +
                    " (0 is the PC format fvm reads; 257 is the old Macintosh one): save it from MountainsMap again");
  }
  if (studiable != kSurSurface) {
    FailReading(name, "holds a studiable of type " + std::to_string(studiable) +
                          "; fvm reads SUR surfaces (type 2): export the surface alone");
  }
  if (bits != 16 && bits != 32) {
    FailReading(name, "has " + std::to_string(bits) + " bits per point; SUR surfaces have 16 or 32");
  }
  if (per_line < 1 || lines < 1 || static_cast<std::uint64_t>(per_line * lines) > kMaxPoints) {
    FailReading(name, "says " + std::to_string(per_line) + " points per line and " + std::to_string(lines) +
                          " lines, not a grid fvm can hold; " + kSurReexport);
  }
  if (!(dx > 0.0) || !(dy > 0.0) || !std::isfinite(dx) || !std::isfinite(dy) || !std::isfinite(dz) || dz == 0.0 ||
      !std::isfinite(z_offset)) {
    FailReading(name, "the x, y, z spacings (" + FormatShortest(dx) + ", " + FormatShortest(dy) + ", " +
                          FormatShortest(dz) + ") or the z offset are not usable numbers; " + kSurReexport);
  }
  if (inverted < 0 || inverted > 3) {
    FailReading(name, "its inversion code is " + std::to_string(inverted) + ", not 0 to 3; " + kSurReexport);
  }
  const double mm_x = SurUnit(name, "the x step unit", p + 180);
  const double mm_y = SurUnit(name, "the y step unit", p + 196);
  const double mm_z = SurUnit(name, "the z step unit", p + 212);

  const std::uint64_t n = static_cast<std::uint64_t>(per_line * lines);
  const std::size_t size = static_cast<std::size_t>(bits / 8);
  const std::size_t data_at = kSurHeaderSize + comment + private_zone;
  if (data_at > bytes.size()) {
    FailReading(name, "its comment and private zones (" + std::to_string(comment) + " + " +
                          std::to_string(private_zone) + " bytes) run past the end of the file; " + kSurReexport);
  }
  std::string inflated;
  const char* counts = bytes.data() + data_at;
  if (compressed) {
    inflated = InflateSurStreams(bytes, data_at, compressed_size, n * size, name);
    counts = inflated.data();
    if (inflated.size() != n * size) {
      FailReading(name, "the compressed streams inflate to " + std::to_string(inflated.size()) + " bytes where " +
                            std::to_string(per_line) + " x " + std::to_string(lines) + " points need " +
                            std::to_string(n * size) + "; " + kSurReexport);
    }
  } else if (bytes.size() - data_at < n * size) {
    FailReading(name, std::to_string(per_line) + " x " + std::to_string(lines) + " points of " + std::to_string(bits) +
                          " bits need " + std::to_string(n * size) + " bytes after the header, but " +
                          std::to_string(bytes.size() - data_at) + " follow; " + kSurReexport);
  }

  HeightMap map;
  map.size_x = static_cast<int>(per_line);
  map.size_y = static_cast<int>(lines);
  map.dx_mm = dx * mm_x;
  map.dy_mm = dy * mm_y;
  const std::string object = FixedText(p + 20, 30);
  map.source = std::string(compressed ? "Digital Surf SUR (compressed)" : "Digital Surf SUR") +
               (object.empty() ? "" : ", " + object);
  if (objects > 1)
    map.notes.push_back("it holds " + std::to_string(objects) + " objects; the first, a surface, is read");
  // The inversion code, as Gwyddion 2.62 (surffile.c) applies it: 1 the heights inverted, 2 also mirrored left to
  // right, 3 also mirrored top to bottom. Gwyddion inverts about the map's mean; fvm negates the counts and keeps the
  // file's z offset (the two differ by a constant height).
  const double mm_per_count = (inverted != 0 ? -dz : dz) * mm_z;
  const double offset_mm = z_offset * mm_z;
  const std::int64_t invalid = static_cast<std::int64_t>(declared_min) - 2;
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t count =
        bits == 16 ? LoadBytes<std::int16_t>(counts + 2 * i) : LoadBytes<std::int32_t>(counts + 4 * i);
    const std::size_t col = i % static_cast<std::size_t>(per_line), row = i / static_cast<std::size_t>(per_line);
    const std::size_t to_col = inverted == 2 ? static_cast<std::size_t>(per_line) - 1 - col : col;
    const std::size_t to_row = inverted == 3 ? static_cast<std::size_t>(lines) - 1 - row : row;
    map.z_mm[to_row * static_cast<std::size_t>(per_line) + to_col] =
        (non_measured && count == invalid) ? std::numeric_limits<double>::quiet_NaN()
                                           : static_cast<double>(count) * mm_per_count + offset_mm;
  }
  if (inverted != 0) {
    static constexpr const char* kHow[] = {"", "inverted", "inverted and mirrored left to right",
                                           "inverted and mirrored top to bottom"};
    map.notes.push_back(std::string("its inversion code is ") + std::to_string(inverted) + ": the heights are read " +
                        kHow[inverted] + ", as Gwyddion reads them");
  }
  return map;
}

HeightMap ReadDigitalSurfSur(const std::filesystem::path& path) {
  return ParseDigitalSurfSur(ReadFileBytes(path), path.string());
}

}  // namespace fvm::imaging
