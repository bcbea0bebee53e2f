#include "imaging/io/image_codec.h"

#include "imaging/io/plugin_loader.h"

namespace fvm::imaging {

const ImageCodec& LoadImageCodec(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_image_oiio.so", "fvm_image_codec_v1", "OpenImageIO",
                                      "libopenimageio2.4"};
  return *static_cast<const ImageCodec*>(LoadPlugin(kPlugin, action));
}

}  // namespace fvm::imaging
