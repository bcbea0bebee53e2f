#include "imaging/io/cloud_codec.h"

#include "imaging/io/plugin_loader.h"

namespace fvm::imaging {

const CloudCodec& LoadCloudCodec(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_cloud_pcl.so", "fvm_cloud_codec_v1", "PCL", "libpcl-io1.13"};
  return *static_cast<const CloudCodec*>(LoadPlugin(kPlugin, action));
}

}  // namespace fvm::imaging
