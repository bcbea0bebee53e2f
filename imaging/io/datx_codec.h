#pragma once
// What a Zygo DATX (an HDF5 file) holds, behind a small std-typed interface, so that fvm_imaging does not link
// HDF5: the HDF5 side lives in the plugin libfvm_datx_hdf5.so (imaging/io/plugins/hdf5_datx_codec.cc), loaded the
// first time a command reads a .datx. The plugin finds the datasets and reads their numbers and attributes as they
// are; it never interprets them and never throws: imaging/io/zygo_datx.cc does both.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fvm::imaging {

// A DATX "converter" attribute (compound Category, BaseUnit, Parameters): how one axis's numbers become a length.
struct DatxConverter {
  std::string category;            // "LateralCat", "HeightCat"
  std::string base_unit;           // "Pixels", "NanoMeters", ...
  std::vector<double> parameters;  // for a lateral axis, parameters[1] is metres per pixel
};

// One two-dimensional dataset with its attributes.
struct DatxDataset {
  std::string path;                // where in the HDF5 file: "/Data/Surface/{...}"
  std::uint64_t rows = 0, cols = 0;
  std::string type_name;           // "float32", "int32", ... as stored
  std::vector<double> values;      // rows x cols, row by row as stored
  std::map<std::string, std::vector<double>> numbers;  // numeric attributes ("No Data", "Wavelength", ...)
  std::map<std::string, std::string> texts;            // string attributes, their first string ("Unit")
  std::map<std::string, DatxConverter> converters;     // "X Converter", "Y Converter", "Z Converter"
};

struct DatxContent {
  DatxDataset surface;
  std::optional<DatxDataset> intensity;
};

// The plugin's function table (entry point "fvm_datx_codec_v1").
struct DatxCodec {
  // Reads the surface (the first dataset of /Data/Surface, else /Measurement/Surface) and the intensity if any
  // (likewise under Intensity) from the file's bytes. A dataset of more than `max_points` values is not read.
  // Returns false with `error` set ("not an HDF5 file", "no /Data/Surface", ...) when they cannot be read.
  bool (*read)(const std::string& bytes, std::uint64_t max_points, DatxContent* content, std::string* error);
};

// The codec, loading the plugin on first use; `action` says what needed it ("reading scan.datx"). When the plugin
// cannot be loaded, throws InputError "<action> needs HDF5: ... could not be loaded (...); install ...".
const DatxCodec& LoadDatxCodec(std::string_view action);

}  // namespace fvm::imaging
