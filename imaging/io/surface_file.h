#pragma once
// Any surface or point-cloud file fvm reads, recognised by its content first (zip for X3P, the AL3D
// signature, TIFF/EXR/PNG magic, PCD and PLY headers) and its extension second, read into a height map or a
// point cloud. The one entry point for commands that take "a measurement file" (fvm info, fvm fit).

#include <filesystem>
#include <optional>
#include <string>

#include "imaging/height_map.h"
#include "imaging/io/height_map_image.h"
#include "imaging/point_cloud.h"
#include "imaging/io/point_cloud_io.h"

namespace fvm::imaging {

enum class SurfaceFormat { kX3p, kAl3d, kImage, kPcd, kPly, kXyz };

// "x3p", "al3d", "image", "pcd", "ply", "xyz".
std::string FormatName(SurfaceFormat format);
bool IsPointCloudFormat(SurfaceFormat format);

// Throws InputError when the file is missing, empty, or neither its content nor its extension is one fvm reads.
SurfaceFormat DetectSurfaceFormat(const std::filesystem::path& path);

struct SurfaceReadOptions {
  HeightMapImageOptions image;
  PointCloudReadOptions cloud;

  void Check() const;
};

// Exactly one of height_map and cloud is set: a height map for X3P, AL3D and images, a cloud for PCD, PLY
// and XYZ.
struct Surface {
  SurfaceFormat format = SurfaceFormat::kX3p;
  std::optional<HeightMap> height_map;
  std::optional<PointCloud> cloud;
};

// Throws InputError naming the file for anything wrong with it.
Surface ReadSurface(const std::filesystem::path& path, const SurfaceReadOptions& options = {});

}  // namespace fvm::imaging
