// The PCD/PLY writer on PCL, built as the plugin libfvm_cloud_pcl.so (see imaging/io/cloud_codec.h). Reading is
// fvm's own (pcd_file.h, ply_file.h: PCL crashes on damaged headers). Every failure here, exceptions included,
// comes back as text, so that no exception has to cross the plugin boundary.

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

constexpr CloudCodec kCodec{&Write};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_cloud_codec_v1() { return &fvm::imaging::kCodec; }
