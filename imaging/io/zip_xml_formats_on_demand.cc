// The zip- and XML-based surface formats as the fvm executable links them: each function forwards to the plugin
// libfvm_zip_xml_formats.so, loaded on the first call (imaging/io/zip_xml_formats.h says why and how).

#include <string>

#include "imaging/io/plugin_loader.h"
#include "imaging/io/zip_xml_formats.h"

namespace fvm::imaging {

const ZipXmlFormats& LoadZipXmlFormats(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_zip_xml_formats.so", "fvm_zip_xml_formats_v1", "libzip and pugixml",
                                      "libzip4 (and libpugixml1v5, libssl3)"};
  return *static_cast<const ZipXmlFormats*>(LoadPlugin(kPlugin, action));
}

HeightMap ReadX3p(const std::filesystem::path& path) {
  return LoadZipXmlFormats("reading " + path.string()).read_x3p(path);
}

void WriteX3p(const std::filesystem::path& path, const HeightMap& map, const X3pWriteOptions& options) {
  LoadZipXmlFormats("writing " + path.string()).write_x3p(path, map, options);
}

HeightMap ReadSensofarPlux(const std::filesystem::path& path) {
  return LoadZipXmlFormats("reading " + path.string()).read_sensofar_plux(path);
}

HeightMap ReadOlympusLext(const std::filesystem::path& path) {
  return LoadZipXmlFormats("reading " + path.string()).read_olympus_lext(path);
}

}  // namespace fvm::imaging
