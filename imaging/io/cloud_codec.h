#pragma once
// Writing PCD and PLY files behind a small std-typed interface, so that fvm_imaging does not link PCL (and VTK
// behind it): the codec lives in the plugin libfvm_cloud_pcl.so (imaging/io/plugins/pcl_cloud_codec.cc), loaded
// the first time a command writes a PCD or PLY file. Reading them, and XYZ/CSV text, never loads it.
//
// The plugin never throws: failures come back as text, and point_cloud_io.cc turns them into InputError.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace fvm::imaging {

// The numeric type of one field, with PCL's codes (pcl::PCLPointField).
enum class CloudFieldType : std::uint8_t {
  kUnknown = 0, kInt8 = 1, kUint8 = 2, kInt16 = 3, kUint16 = 4, kInt32 = 5, kUint32 = 6, kFloat32 = 7, kFloat64 = 8
};

// Bytes per value; 0 for kUnknown.
constexpr std::size_t CloudFieldSize(CloudFieldType type) {
  switch (type) {
    case CloudFieldType::kInt8: case CloudFieldType::kUint8: return 1;
    case CloudFieldType::kInt16: case CloudFieldType::kUint16: return 2;
    case CloudFieldType::kInt32: case CloudFieldType::kUint32: case CloudFieldType::kFloat32: return 4;
    case CloudFieldType::kFloat64: return 8;
    default: return 0;
  }
}

struct CloudField {
  std::string name;
  std::uint32_t offset = 0;  // in the point record, bytes
  CloudFieldType type = CloudFieldType::kUnknown;
  std::uint32_t count = 1;
};

// A cloud as records of bytes, the way PCD and PLY store it (pcl::PCLPointCloud2 in std types).
struct CloudBlob {
  std::uint32_t width = 0, height = 0;
  std::uint32_t point_step = 0, row_step = 0;  // bytes per point, per row
  bool is_dense = false;
  std::vector<CloudField> fields;
  std::vector<std::uint8_t> data;
};

enum class CloudFileType { kPcd, kPly };

// The plugin's function table (entry point "fvm_cloud_codec_v1"). Reading is fvm's own (pcd_file.h, ply_file.h),
// which checks a damaged file whole where PCL's reader crashes. Returns false and sets `error` on failure.
struct CloudCodec {
  // Binary, without viewpoint.
  bool (*write)(const std::filesystem::path& path, CloudFileType type, const CloudBlob& blob, std::string* error);
};

// The codec, loading the plugin on first use; `action` says what needed it ("writing scan.pcd"). Throws
// InputError "<action> needs PCL: ... could not be loaded (...); install the Debian package ..." when it cannot.
const CloudCodec& LoadCloudCodec(std::string_view action);

}  // namespace fvm::imaging
