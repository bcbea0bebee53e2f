#pragma once
// Any surface or point-cloud file fvm reads, recognised by its content first (zip for X3P, the AL3D
// signature, ISO 25178-71 SDF's aISO-1.0 / bISO-1.0, the instrument signatures of Zygo MetroPro, Wyko OPD, Digital
// Surf SUR, GelSight TMD, Sensofar PLU and Keyence VK4, HDF5's for Zygo DATX, .lext before TIFF/EXR/PNG magic, PCD and PLY headers) and its extension second, read
// into a height map or a point cloud. The one entry point for commands that take "a measurement file" (fvm info,
// fvm fit, fvm correct, fvm calibrate RAW, Python's read_surface).

#include <filesystem>
#include <optional>
#include <string>

#include "imaging/height_map.h"
#include "imaging/io/height_map_image.h"
#include "imaging/point_cloud.h"
#include "imaging/io/point_cloud_io.h"

namespace fvm::imaging {

enum class SurfaceFormat {
  kX3p, kAl3d, kImage, kPcd, kPly, kXyz, kSdf,
  // Other instruments' exports, read only: Sensofar PLU, Zygo MetroPro DAT, Wyko OPD, Digital Surf SUR, NMS,
  // GelSight TMD, Sensofar PLUx, Keyence VK4, Zygo DATX, Olympus
  // LEXT.
  kPlu, kMetroPro, kOpd, kSur, kNms, kTmd, kPlux, kVk4, kDatx, kLext
};

// "x3p", "al3d", "image", "pcd", "ply", "xyz", "sdf", "plu", "metropro", "opd", "sur", "nms", "tmd", "plux", "vk4",
// "datx", "lext".
std::string FormatName(SurfaceFormat format);
bool IsPointCloudFormat(SurfaceFormat format);

// The format a file of this name is written in, by its extension alone (for outputs): .x3p, .al3d, .sdf,
// .tif/.tiff/.exr/.png, .pcd, .ply, .xyz/.csv/.txt/.asc/.pts/.ds; nullopt for anything else.
std::optional<SurfaceFormat> SurfaceFormatOfName(const std::filesystem::path& path);

// Throws InputError when the file is missing, empty, or neither its content nor its extension is one fvm reads.
SurfaceFormat DetectSurfaceFormat(const std::filesystem::path& path);

struct SurfaceReadOptions {
  HeightMapImageOptions image;
  PointCloudReadOptions cloud;

  void Check() const;
};

// Exactly one of height_map and cloud is set: a height map for X3P, AL3D, SDF, images and the instruments' exports,
// a cloud for PCD, PLY and XYZ.
struct Surface {
  SurfaceFormat format = SurfaceFormat::kX3p;
  std::optional<HeightMap> height_map;
  std::optional<PointCloud> cloud;
};

// Throws InputError naming the file for anything wrong with it.
Surface ReadSurface(const std::filesystem::path& path, const SurfaceReadOptions& options = {});

// A height map written by the extension: X3P (float64 heights, D), AL3D (float32) or a float32 image (TIFF,
// EXR). Atomically. Throws InputError for another extension.
void WriteHeightMap(const std::filesystem::path& path, const HeightMap& map);

}  // namespace fvm::imaging
