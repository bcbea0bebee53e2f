#pragma once
// Zygo DATX files as Mx writes them, for the DATX reader's tests and the fuzzer's seed (test-only: fvm writes no
// DATX; the layout is the one imaging/io/zygo_datx.h documents). Written with HDF5's C library directly, not
// through fvm's plugin, into memory (HDF5's core driver), and returned as the file's bytes:
//   /MetaData                          compound (Source, Link, Destination) rows naming the surface's path
//   /Data/Surface/{GUID}               float32 rows x cols, "No Data" = FLT_MAX where a point is invalid
//     "Unit", "No Data", "X Converter", "Y Converter", "Z Converter", "Wavelength",
//     "Interferometric Scale Factor", "Obliquity Factor"
//   /Data/Intensity/{GUID}             uint16 grey levels (GreyOf), when asked for
// Heights are written in nanometres, or in fringes of 632.8 nm at scale factor 0.5 (a surface's double pass).

#include <hdf5.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "imaging/height_map.h"
#include "tests/support/instrument_files.h"

namespace fvm::imaging::testing {

enum class DatxUnit { kNanoMeters, kFringes };

struct DatxWriteOptions {
  DatxUnit unit = DatxUnit::kNanoMeters;
  bool intensity = true;
  bool nx2_layout = false;  // /Measurement/Surface instead of /Data/Surface/{GUID}
  // A second dataset in /Data/Surface whose name sorts first, holding the heights plus 1 um: what a file saved again
  // after processing may hold beside the measurement. /MetaData names the measurement, unless `metadata` is false.
  bool earlier_copy = false;
  bool metadata = true;
  bool fixed_parameters = false;  // the converters' Parameters as a fixed array of doubles, not a variable-length list
};

inline constexpr double kDatxWavelengthM = 632.8e-9, kDatxScaleFactor = 0.5;

namespace datx_detail {

inline hid_t VariableString() {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  return type;
}

inline void PutText(hid_t object, const char* name, const char* text) {
  const hid_t type = VariableString();
  const hsize_t one = 1;
  const hid_t space = H5Screate_simple(1, &one, nullptr);
  const hid_t attribute = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attribute, type, &text);
  H5Aclose(attribute), H5Sclose(space), H5Tclose(type);
}

inline void PutNumber(hid_t object, const char* name, double value) {
  const hsize_t one = 1;
  const hid_t space = H5Screate_simple(1, &one, nullptr);
  const hid_t attribute = H5Acreate2(object, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attribute, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attribute), H5Sclose(space);
}

// The converter compound; its Parameters a variable-length list of doubles, or with `fixed_array` a fixed array of
// them (both are HDF5's ways of storing a list; the reader takes either).
inline void PutConverter(hid_t object, const char* name, const char* category, const char* unit,
                         std::vector<double> parameters, bool fixed_array = false) {
  const hid_t text = VariableString();
  const hsize_t count = parameters.size();
  const hid_t memory_doubles =
      fixed_array ? H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, &count) : H5Tvlen_create(H5T_NATIVE_DOUBLE);
  const std::size_t parameters_at = 2 * sizeof(const char*);
  const std::size_t parameters_size = fixed_array ? count * sizeof(double) : sizeof(hvl_t);
  const hid_t type = H5Tcreate(H5T_COMPOUND, parameters_at + parameters_size);
  H5Tinsert(type, "Category", 0, text);
  H5Tinsert(type, "BaseUnit", sizeof(const char*), text);
  H5Tinsert(type, "Parameters", parameters_at, memory_doubles);
  std::vector<unsigned char> value(parameters_at + parameters_size);
  std::memcpy(value.data(), &category, sizeof category);
  std::memcpy(value.data() + sizeof(const char*), &unit, sizeof unit);
  const hvl_t list{parameters.size(), parameters.data()};
  if (fixed_array) {
    std::memcpy(value.data() + parameters_at, parameters.data(), parameters_size);
  } else {
    std::memcpy(value.data() + parameters_at, &list, sizeof list);
  }
  const hsize_t one = 1;
  const hid_t space = H5Screate_simple(1, &one, nullptr);
  const hid_t attribute = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attribute, type, value.data());
  H5Aclose(attribute), H5Sclose(space), H5Tclose(type), H5Tclose(memory_doubles), H5Tclose(text);
}

inline hid_t Dataset(hid_t file, const std::string& path, hid_t file_type, hid_t memory_type, int rows, int cols,
                     const void* data) {
  const hsize_t dims[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  const hid_t space = H5Screate_simple(2, dims, nullptr);
  const hid_t links = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(links, 1);
  const hid_t dataset = H5Dcreate2(file, path.c_str(), file_type, space, links, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(dataset, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  H5Pclose(links), H5Sclose(space);
  return dataset;
}

}  // namespace datx_detail

// The file's bytes. The map's dx, dy are the converters' pixel; invalid points are written as No Data.
inline std::string BuildDatx(const HeightMap& map, const DatxWriteOptions& options = {}) {
  using namespace datx_detail;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_fapl_core(access, 1 << 16, 0);
  const hid_t file = H5Fcreate("synthetic.datx", H5F_ACC_TRUNC, H5P_DEFAULT, access);
  if (file < 0) throw std::runtime_error("BuildDatx: HDF5 cannot create a file in memory");
  const std::string surface_path =
      options.nx2_layout ? "/Measurement/Surface" : "/Data/Surface/{3B8D1D1C-5A6E-4F52-9C3A-0F2B6E1D7A44}";
  const std::string intensity_path =
      options.nx2_layout ? "/Measurement/Intensity" : "/Data/Intensity/{9E21B0B4-77F1-4C0D-8F0E-5D2A3C4B1E90}";
  if (options.metadata) {
    struct Row {
      const char* source;
      const char* link;
      const char* destination;
    };
    const Row rows[3] = {{"Root", "Measurement", "{M}"}, {"{M}", "Surface", "{S}"}, {"{S}", "Path", surface_path.c_str()}};
    const hid_t text = VariableString();
    const hid_t type = H5Tcreate(H5T_COMPOUND, sizeof(Row));
    H5Tinsert(type, "Source", HOFFSET(Row, source), text);
    H5Tinsert(type, "Link", HOFFSET(Row, link), text);
    H5Tinsert(type, "Destination", HOFFSET(Row, destination), text);
    const hsize_t three = 3;
    const hid_t space = H5Screate_simple(1, &three, nullptr);
    const hid_t metadata = H5Dcreate2(file, "/MetaData", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(metadata, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows);
    H5Dclose(metadata), H5Sclose(space), H5Tclose(type), H5Tclose(text);
  }
  const double metres_per_value =
      options.unit == DatxUnit::kFringes ? kDatxWavelengthM * kDatxScaleFactor : 1e-9;
  std::vector<float> values(map.z_mm.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    values[i] = std::isfinite(map.z_mm[i]) ? static_cast<float>(map.z_mm[i] / 1000.0 / metres_per_value) : FLT_MAX;
  }
  const auto put_surface = [&](const std::string& path, const std::vector<float>& counts) {
    const hid_t surface =
        Dataset(file, path, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, map.size_y, map.size_x, counts.data());
    PutText(surface, "Unit", options.unit == DatxUnit::kFringes ? "Fringes" : "NanoMeters");
    PutNumber(surface, "No Data", FLT_MAX);
    const bool fixed = options.fixed_parameters;
    PutConverter(surface, "X Converter", "LateralCat", "Pixels", {0.0, map.dx_mm / 1000.0, 0.0, 0.0}, fixed);
    PutConverter(surface, "Y Converter", "LateralCat", "Pixels", {0.0, map.dy_mm / 1000.0, 0.0, 0.0}, fixed);
    PutConverter(surface, "Z Converter", "HeightCat", options.unit == DatxUnit::kFringes ? "Fringes" : "NanoMeters",
                 {kDatxWavelengthM, kDatxScaleFactor, 1.0}, fixed);
    PutNumber(surface, "Wavelength", kDatxWavelengthM);
    PutNumber(surface, "Interferometric Scale Factor", kDatxScaleFactor);
    PutNumber(surface, "Obliquity Factor", 1.0);
    H5Dclose(surface);
  };
  if (options.earlier_copy) {
    std::vector<float> copy(values);
    for (float& v : copy) v = v == FLT_MAX ? v : v + static_cast<float>(1e-6 / metres_per_value);
    put_surface("/Data/Surface/{0000C0DE-0000-0000-0000-000000000000}", copy);
  }
  put_surface(surface_path, values);
  if (options.intensity) {
    std::vector<std::uint16_t> grey(map.z_mm.size());
    for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = GreyOf(i);
    H5Dclose(Dataset(file, intensity_path, H5T_STD_U16LE, H5T_NATIVE_UINT16, map.size_y, map.size_x, grey.data()));
  }
  H5Fflush(file, H5F_SCOPE_GLOBAL);
  const ssize_t size = H5Fget_file_image(file, nullptr, 0);
  std::string bytes(static_cast<std::size_t>(size > 0 ? size : 0), '\0');
  if (size <= 0 || H5Fget_file_image(file, bytes.data(), bytes.size()) != size) {
    throw std::runtime_error("BuildDatx: HDF5 gave no file image");
  }
  H5Fclose(file), H5Pclose(access);
  return bytes;
}

}  // namespace fvm::imaging::testing
