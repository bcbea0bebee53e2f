#pragma once
// X3P ([ISO 25178-72], the OpenGPS container): a zip archive with main.xml (axes, matrix dimensions, the point
// data inline or as a link to bindata/data.bin with its MD5), optional bindata/valid.bin (one validity bit per
// point) and md5checksum.hex (the MD5 of main.xml). X3P is in metres; the height map is in mm.
//
// The reader takes surfaces on a regular grid (FeatureType SUR or PRF, incremental X and Y axes, SizeZ 1) with
// Z of type I, L, F or D; it verifies every checksum the file carries. Invalid points (NaN, empty Datum, a
// cleared validity bit) become NaN.

#include <filesystem>
#include <string>

#include "imaging/height_map.h"

namespace fvm::imaging {

enum class X3pDataType { kInt16, kInt32, kFloat32, kFloat64 };  // X3P's I, L, F, D

struct X3pWriteOptions {
  X3pDataType z_type = X3pDataType::kFloat64;  // D keeps every float height exactly
  double z_increment_mm = 0.0;                 // the quantum of I and L (required for them); unused for F and D
  bool binary = true;                          // bindata/data.bin; false writes an inline DataList
  std::string date;                            // Record2 Date (xsd:dateTime); empty: the current UTC time
  std::string creator = "fvm";
  std::string manufacturer = "unknown";  // Record2 Instrument: the instrument that measured the surface
  std::string model = "unknown";
  std::string comment;

  // Throws InputError when the options cannot describe a file (integer type without an increment).
  void Check() const;
};

// Throws InputError naming the file for anything wrong with it (not a zip, no main.xml, a checksum that does
// not match, sizes that disagree with the data, unsupported layouts).
HeightMap ReadX3p(const std::filesystem::path& path);
// The same from the file's bytes; `name` is what errors call the file.
HeightMap ParseX3p(std::string bytes, const std::string& name);

// Written atomically. Throws InputError when the heights do not fit the chosen integer type.
void WriteX3p(const std::filesystem::path& path, const HeightMap& map, const X3pWriteOptions& options = {});
// The file's bytes.
std::string BuildX3p(const HeightMap& map, const X3pWriteOptions& options = {});

}  // namespace fvm::imaging
