#include "imaging/io/surface_file.h"

#include <cctype>
#include <string_view>

#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/al3d.h"
#include "core/file_io.h"
#include "imaging/io/sdf.h"
#include "imaging/io/x3p.h"

namespace fvm::imaging {
namespace {

bool StartsWith(std::string_view text, std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; }


std::optional<SurfaceFormat> FromContent(std::string_view head) {
  using namespace std::string_view_literals;
  if (StartsWith(head, "PK\x03\x04"sv) || StartsWith(head, "PK\x05\x06"sv)) return SurfaceFormat::kX3p;
  if (StartsWith(head, "AliconaImaging")) return SurfaceFormat::kAl3d;
  if (StartsWith(head, "aISO-1.0") || StartsWith(head, "bISO-1.0")) return SurfaceFormat::kSdf;
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
  if (const std::optional<SurfaceFormat> format = FromContent(head)) return *format;
  if (const std::optional<SurfaceFormat> format = FromExtension(path)) return *format;
  if (LooksLikeText(head)) return SurfaceFormat::kXyz;
  throw InputError(path.string() +
                   ": not a format fvm reads; it reads X3P, Alicona AL3D, ISO 25178-71 SDF, height-map images (TIFF, EXR, PNG), "
                   "PCD, PLY and XYZ/CSV text");
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
