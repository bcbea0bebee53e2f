// The PCD/PLY codec on PCL, built as the plugin libfvm_cloud_pcl.so (see imaging/io/cloud_codec.h). The header
// checks and the messages stay in point_cloud_io.cc; every failure here, exceptions included, comes back as
// text, so that no exception has to cross the plugin boundary.

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <exception>
#include <string>

#include "imaging/io/cloud_codec.h"

namespace fvm::imaging {
namespace {

// PCL reports problems on the console in its own words; fvm's name the file and what to do instead.
class QuietPcl {
 public:
  QuietPcl() : previous_(pcl::console::getVerbosityLevel()) { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); }
  ~QuietPcl() { pcl::console::setVerbosityLevel(previous_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL previous_;
};

CloudFieldType FromPcl(std::uint8_t datatype) {
  return datatype >= 1 && datatype <= 8 ? static_cast<CloudFieldType>(datatype) : CloudFieldType::kUnknown;
}

bool Read(const std::filesystem::path& path, CloudFileType type, CloudBlob* blob, std::string* error) {
  const QuietPcl quiet;
  try {
    pcl::PCLPointCloud2 cloud;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    const int result = type == CloudFileType::kPcd
                           ? pcl::PCDReader().read(path.string(), cloud, origin, orientation, version, 0)
                           : pcl::PLYReader().read(path.string(), cloud, origin, orientation, version, 0);
    if (result < 0) {
      error->clear();
      return false;
    }
    blob->width = cloud.width;
    blob->height = cloud.height;
    blob->point_step = cloud.point_step;
    blob->row_step = cloud.row_step;
    blob->is_dense = cloud.is_dense;
    blob->fields.clear();
    for (const pcl::PCLPointField& field : cloud.fields) {
      blob->fields.push_back({field.name, field.offset, FromPcl(field.datatype), field.count});
    }
    blob->data = std::move(cloud.data);
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

bool Write(const std::filesystem::path& path, CloudFileType type, const CloudBlob& blob, std::string* error) {
  const QuietPcl quiet;
  try {
    pcl::PCLPointCloud2 cloud;
    cloud.width = blob.width;
    cloud.height = blob.height;
    cloud.point_step = blob.point_step;
    cloud.row_step = blob.row_step;
    cloud.is_dense = blob.is_dense;
    for (const CloudField& field : blob.fields) {
      pcl::PCLPointField out;
      out.name = field.name;
      out.offset = field.offset;
      out.datatype = static_cast<std::uint8_t>(field.type);
      out.count = field.count;
      cloud.fields.push_back(out);
    }
    cloud.data = blob.data;
    const int result = type == CloudFileType::kPcd
                           ? pcl::PCDWriter().writeBinary(path.string(), cloud)
                           : pcl::PLYWriter().writeBinary(path.string(), cloud, Eigen::Vector4f::Zero(),
                                                          Eigen::Quaternionf::Identity(), false);
    if (result < 0) error->clear();
    return result >= 0;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

constexpr CloudCodec kCodec{&Read, &Write};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_cloud_codec_v1() { return &fvm::imaging::kCodec; }
