// The plugin libfvm_zip_xml_formats.so: the surface formats that need libzip, pugixml or OpenSSL, linked in whole
// (fvm_imaging_zip_xml), behind their table (imaging/io/zip_xml_formats.h).

#include "imaging/io/zip_xml_formats.h"

namespace fvm::imaging {
namespace {

constexpr ZipXmlFormats kZipXmlFormats{
    &ReadX3p,
    &WriteX3p,
    &ReadSensofarPlux,
    &ReadOlympusLext,
};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_zip_xml_formats_v1() {
  return &fvm::imaging::kZipXmlFormats;
}
