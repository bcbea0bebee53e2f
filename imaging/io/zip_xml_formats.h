#pragma once
// The surface formats that need libzip, pugixml or OpenSSL (X3P read and written, Sensofar PLUx, Olympus LEXT),
// seen through one table of their entry points, so that the fvm executable maps those libraries only when a
// command first meets such a file. libzip pulls libcrypto (4.5 MB, thousands of relocations) and libbz2: with
// pugixml they were a good part of the dynamic loader's work before main of every command, and the commands that
// never read or write a surface (calibrate on centre exports, verify, diff, ...) should not pay it (issue 47).
//
// How it is built (imaging/CMakeLists.txt), as the OpenCV code is (imaging/opencv_imaging.h): the files of these
// formats form the static library fvm_imaging_zip_xml, linked into whatever links fvm_imaging (tests, benchmarks,
// the Python module) and into the plugin libfvm_zip_xml_formats.so (io/plugins/zip_xml_formats.cc), which returns
// this table. The fvm executable links zip_xml_formats_on_demand.cc instead: the same functions, each forwarded
// through the table of the plugin, loaded on the first call (io/plugin_loader.h). Call sites do not change.
//
// A function of these files newly called from the fvm executable's code (surface_file.cc, artefacts/, workflows/,
// fvm/) needs a member here, its line in the plugin's table and its forwarder in zip_xml_formats_on_demand.cc;
// without them the executable does not link ("undefined reference").

#include <string_view>

#include "imaging/io/olympus_lext.h"
#include "imaging/io/sensofar_plux.h"
#include "imaging/io/x3p.h"

namespace fvm::imaging {

// The plugin's function table (entry point "fvm_zip_xml_formats_v1").
struct ZipXmlFormats {
  decltype(&ReadX3p) read_x3p;
  decltype(&WriteX3p) write_x3p;
  decltype(&ReadSensofarPlux) read_sensofar_plux;
  decltype(&ReadOlympusLext) read_olympus_lext;
};

// The table, loading the plugin on first use. `action` says what needed it ("reading a.x3p"); when the plugin
// cannot be loaded, throws InputError "<action> needs libzip and pugixml: libfvm_zip_xml_formats.so could not be
// loaded (...); install the Debian package ...".
const ZipXmlFormats& LoadZipXmlFormats(std::string_view action);

}  // namespace fvm::imaging
