#pragma once
// Point clouds in files: PCD and PLY (read by fvm's own strict readers, written through PCL; any numeric x, y, z
// fields, other fields ignored), and plain XYZ/CSV text (x y z per line, separated by blanks, commas or
// semicolons; '#' comments; an optional header line naming the columns, or a first line holding only the point
// count, as NIST's ATS .ds files have it; more columns ignored). Coordinates are mm unless the options say otherwise.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "imaging/point_cloud.h"

namespace fvm::imaging {

struct PointCloudReadOptions {
  double mm_per_unit = 1.0;  // 1000 for clouds exported in metres, 0.001 for micrometres

  // Throws InputError unless mm_per_unit is positive and finite.
  void Check() const;
};

enum class PointCloudFormat { kPcd, kPly, kXyz };

// By the path's extension: .pcd, .ply, anything else is XYZ text.
PointCloudFormat PointCloudFormatOf(const std::filesystem::path& path);

// Reads `path` as `format`. Throws InputError naming the file (and line, for text) when it cannot be read,
// has no x, y, z, or holds no points.
PointCloud ReadPointCloud(const std::filesystem::path& path, PointCloudFormat format,
                          const PointCloudReadOptions& options = {});
PointCloud ReadPointCloud(const std::filesystem::path& path, const PointCloudReadOptions& options = {});

// XYZ text already in memory; `name` is what errors call it. A "# grid W x H" comment (as WritePointCloud
// writes it) restores an organised cloud when the point count matches.
PointCloud ParseXyz(std::string_view text, const std::string& name, const PointCloudReadOptions& options = {});

// A value per point beside x, y, z (a corrected cloud's standard uncertainties u_x, u_y, u_z, mm).
struct PointField {
  std::string name;
  std::vector<double> values;  // one per point
};

// Binary PCD or PLY with double coordinates, or XYZ text with round-trip exact numbers, by the extension.
// Organised clouds stay organised. `extra` fields become further double properties (PLY), fields (PCD) or
// columns under a header line naming them (XYZ). `comment` (one line) goes into an XYZ file's '#' header; PCL's
// PLY and PCD writers have no place for it. Written atomically.
void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud,
                     const std::vector<PointField>& extra = {}, const std::string& comment = "");

}  // namespace fvm::imaging
