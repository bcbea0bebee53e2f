#include "imaging/io/surface_file.h"

#include <cctype>
#include <string_view>

#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/al3d.h"
#include "core/file_io.h"
#include "imaging/io/digital_surf_sur.h"
#include "imaging/io/gelsight_tmd.h"
#include "imaging/io/keyence_vk4.h"
#include "imaging/io/metropro_dat.h"
#include "imaging/io/nms_file.h"
#include "imaging/io/olympus_lext.h"
#include "imaging/io/sdf.h"
#include "imaging/io/sensofar_plu.h"
#include "imaging/io/sensofar_plux.h"
#include "imaging/io/wyko_opd.h"
#include "imaging/io/x3p.h"
#include "imaging/io/zygo_datx.h"

namespace fvm::imaging {
namespace {

bool StartsWith(std::string_view text, std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; }

// A Sensofar PLU starts with its date as C's asctime writes it ("Mon Apr 19 11:40:13 2021"), NUL-terminated.
bool StartsWithPluDate(std::string_view head) {
  if (head.size() < 25 || head[24] != '\0') return false;
  static constexpr std::string_view kDays = "MonTueWedThuFriSatSun";
  static constexpr std::string_view kMonths = "JanFebMarAprMayJunJulAugSepOctNovDec";
  const std::string_view day = head.substr(0, 3), month = head.substr(4, 3);
  const auto listed = [](std::string_view list, std::string_view word) {
    for (std::size_t i = 0; i + 3 <= list.size(); i += 3) {
      if (list.substr(i, 3) == word) return true;
    }
    return false;
  };
  return listed(kDays, day) && head[3] == ' ' && listed(kMonths, month) && head[7] == ' ' && head[13] == ':' &&
         head[16] == ':';
}


std::optional<SurfaceFormat> FromContent(std::string_view head) {
  using namespace std::string_view_literals;
  if (StartsWith(head, "PK\x03\x04"sv) || StartsWith(head, "PK\x05\x06"sv)) return SurfaceFormat::kX3p;
  if (StartsWith(head, "AliconaImaging")) return SurfaceFormat::kAl3d;
  if (StartsWith(head, "aISO-1.0") || StartsWith(head, "bISO-1.0")) return SurfaceFormat::kSdf;
  if (HasMetroProMagic(std::string(head.substr(0, 4)))) return SurfaceFormat::kMetroPro;
  if (HasWykoOpdDirectory(std::string(head.substr(0, 12)))) return SurfaceFormat::kOpd;
  if (StartsWith(head, "DIGITAL SURF") || StartsWith(head, "DSCOMPRESSED")) return SurfaceFormat::kSur;
  if (StartsWith(head, "Binary TrueMap Data File")) return SurfaceFormat::kTmd;
  if (HasKeyenceVk4Magic(std::string(head.substr(0, 12)))) return SurfaceFormat::kVk4;
  if (HasHdf5Signature(std::string(head.substr(0, 8)))) return SurfaceFormat::kDatx;
  if (StartsWithPluDate(head)) return SurfaceFormat::kPlu;
  if (StartsWith(head, "II*\0"sv) || StartsWith(head, "MM\0*"sv) || StartsWith(head, "\x76\x2f\x31\x01"sv) ||
      StartsWith(head, "\x89PNG"sv)) {
    return SurfaceFormat::kImage;
  }
  if (StartsWith(head, "ply\n") || StartsWith(head, "ply\r\n")) return SurfaceFormat::kPly;
  if (StartsWith(head, "# .PCD") || StartsWith(head, "VERSION") || StartsWith(head, "FIELDS")) {
    return SurfaceFormat::kPcd;
  }
  return std::nullopt;
}

std::optional<SurfaceFormat> FromExtension(const std::filesystem::path& path) {
  const std::string extension = AsciiLower(path.extension().string());
  if (extension == ".x3p") return SurfaceFormat::kX3p;
  if (extension == ".al3d") return SurfaceFormat::kAl3d;
  if (extension == ".sdf") return SurfaceFormat::kSdf;
  if (extension == ".tif" || extension == ".tiff" || extension == ".exr" || extension == ".png") {
    return SurfaceFormat::kImage;
  }
  if (extension == ".pcd") return SurfaceFormat::kPcd;
  if (extension == ".ply") return SurfaceFormat::kPly;
  if (extension == ".xyz" || extension == ".csv" || extension == ".txt" || extension == ".asc" || extension == ".pts" ||
      extension == ".ds") {
    return SurfaceFormat::kXyz;
  }
  return std::nullopt;
}

// Formats fvm reads but does not write, by extension: instruments' exports whose content is not recognised above.
std::optional<SurfaceFormat> ReadOnlyFromExtension(const std::filesystem::path& path) {
  const std::string extension = AsciiLower(path.extension().string());
  if (extension == ".plu") return SurfaceFormat::kPlu;
  if (extension == ".opd") return SurfaceFormat::kOpd;
  if (extension == ".sur") return SurfaceFormat::kSur;
  if (extension == ".nms") return SurfaceFormat::kNms;
  if (extension == ".tmd") return SurfaceFormat::kTmd;
  if (extension == ".plux") return SurfaceFormat::kPlux;
  if (extension == ".vk4") return SurfaceFormat::kVk4;
  if (extension == ".datx") return SurfaceFormat::kDatx;
  if (extension == ".lext") return SurfaceFormat::kLext;
  return std::nullopt;
}

bool LooksLikeText(std::string_view head) {
  for (const char c : head) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 && c != '\n' && c != '\r' && c != '\t') return false;
  }
  return true;
}

}  // namespace

std::string FormatName(SurfaceFormat format) {
  switch (format) {
    case SurfaceFormat::kX3p:
      return "x3p";
    case SurfaceFormat::kAl3d:
      return "al3d";
    case SurfaceFormat::kImage:
      return "image";
    case SurfaceFormat::kPcd:
      return "pcd";
    case SurfaceFormat::kPly:
      return "ply";
    case SurfaceFormat::kSdf:
      return "sdf";
    case SurfaceFormat::kPlu:
      return "plu";
    case SurfaceFormat::kMetroPro:
      return "metropro";
    case SurfaceFormat::kOpd:
      return "opd";
    case SurfaceFormat::kSur:
      return "sur";
    case SurfaceFormat::kNms:
      return "nms";
    case SurfaceFormat::kTmd:
      return "tmd";
    case SurfaceFormat::kPlux:
      return "plux";
    case SurfaceFormat::kVk4:
      return "vk4";
    case SurfaceFormat::kDatx:
      return "datx";
    case SurfaceFormat::kLext:
      return "lext";
    default:
      return "xyz";
  }
}

bool IsPointCloudFormat(SurfaceFormat format) {
  return format == SurfaceFormat::kPcd || format == SurfaceFormat::kPly || format == SurfaceFormat::kXyz;
}

std::optional<SurfaceFormat> SurfaceFormatOfName(const std::filesystem::path& path) { return FromExtension(path); }

void WriteHeightMap(const std::filesystem::path& path, const HeightMap& map) {
  const std::optional<SurfaceFormat> format = FromExtension(path);
  if (format == SurfaceFormat::kX3p) {
    WriteX3p(path, map);
  } else if (format == SurfaceFormat::kAl3d) {
    WriteAl3d(path, map);
  } else if (format == SurfaceFormat::kImage && AsciiLower(path.extension().string()) != ".png") {
    WriteHeightMapImage(path, map);
  } else {
    throw InputError(path.string() + ": a height map is written as .x3p, .al3d, .tif, .tiff or .exr");
  }
}

SurfaceFormat DetectSurfaceFormat(const std::filesystem::path& path) {
  const std::string head = ReadFileHead(path, 64);
  if (head.empty()) throw InputError(path.string() + ": the file is empty; export or copy it again");
  if (const std::optional<SurfaceFormat> by_content = FromContent(head)) {
    // A zip archive is an X3P, unless it is named as Sensofar's PLUx (index.xml and layers, no main.xml); a TIFF
    // is an image, unless it is named as Olympus' LEXT (pages named in their descriptions).
    const std::optional<SurfaceFormat> named = ReadOnlyFromExtension(path);
    if (*by_content == SurfaceFormat::kX3p && named == SurfaceFormat::kPlux) return SurfaceFormat::kPlux;
    if (*by_content == SurfaceFormat::kImage && named == SurfaceFormat::kLext) return SurfaceFormat::kLext;
    return *by_content;
  }
  if (const std::optional<SurfaceFormat> format = FromExtension(path)) return *format;
  if (const std::optional<SurfaceFormat> format = ReadOnlyFromExtension(path)) return *format;
  if (LooksLikeText(head)) return SurfaceFormat::kXyz;
  throw InputError(path.string() +
                   ": not a format fvm reads; it reads X3P, Alicona AL3D, ISO 25178-71 SDF, Sensofar PLU and "
                   "PLUx, Zygo MetroPro DAT, Wyko OPD, Digital Surf SUR, NMS, GelSight TMD, Keyence VK4, Zygo DATX, Olympus LEXT, height-map images (TIFF, "
                   "EXR, PNG), PCD, PLY and XYZ/CSV text");
}

void SurfaceReadOptions::Check() const {
  image.Check();
  cloud.Check();
}

Surface ReadSurface(const std::filesystem::path& path, const SurfaceReadOptions& options) {
  options.Check();
  Surface surface;
  surface.format = DetectSurfaceFormat(path);
  switch (surface.format) {
    case SurfaceFormat::kX3p:
      surface.height_map = ReadX3p(path);
      break;
    case SurfaceFormat::kAl3d:
      surface.height_map = ReadAl3d(path);
      break;
    case SurfaceFormat::kSdf:
      surface.height_map = ReadSdf(path);
      break;
    case SurfaceFormat::kPlu:
      surface.height_map = ReadSensofarPlu(path);
      break;
    case SurfaceFormat::kMetroPro:
      surface.height_map = ReadMetroProDat(path);
      break;
    case SurfaceFormat::kOpd:
      surface.height_map = ReadWykoOpd(path);
      break;
    case SurfaceFormat::kSur:
      surface.height_map = ReadDigitalSurfSur(path);
      break;
    case SurfaceFormat::kNms:
      surface.height_map = ReadNms(path);
      break;
    case SurfaceFormat::kTmd:
      surface.height_map = ReadGelSightTmd(path);
      break;
    case SurfaceFormat::kPlux:
      surface.height_map = ReadSensofarPlux(path);
      break;
    case SurfaceFormat::kVk4:
      surface.height_map = ReadKeyenceVk4(path);
      break;
    case SurfaceFormat::kDatx:
      surface.height_map = ReadZygoDatx(path);
      break;
    case SurfaceFormat::kLext:
      surface.height_map = ReadOlympusLext(path);
      break;
    case SurfaceFormat::kImage:
      surface.height_map = ReadHeightMapImage(path, options.image);
      break;
    case SurfaceFormat::kPcd:
      surface.cloud = ReadPointCloud(path, PointCloudFormat::kPcd, options.cloud);
      break;
    case SurfaceFormat::kPly:
      surface.cloud = ReadPointCloud(path, PointCloudFormat::kPly, options.cloud);
      break;
    case SurfaceFormat::kXyz:
      surface.cloud = ReadPointCloud(path, PointCloudFormat::kXyz, options.cloud);
      break;
  }
  return surface;
}

}  // namespace fvm::imaging
