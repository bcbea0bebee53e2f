// Writing X3P files (imaging/io/x3p.h): main.xml from the height map's grid, the heights inline or in
// bindata/data.bin with their validity bits, every MD5 the reader checks, all in one zip archive.

#include "imaging/io/x3p.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <limits>
#include <pugixml.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/md5.h"
#include "imaging/io/reader_support.h"
#include "imaging/io/x3p_format.h"
#include "imaging/io/zip_archive.h"

namespace fvm::imaging {
namespace {

constexpr const char* kDataBin = "bindata/data.bin";
constexpr const char* kValidBin = "bindata/valid.bin";
constexpr const char* kNamespace = "http://www.opengps.eu/2008/ISO5436_2";

char TypeCode(X3pDataType type) {
  switch (type) {
    case X3pDataType::kInt16:
      return 'I';
    case X3pDataType::kInt32:
      return 'L';
    case X3pDataType::kFloat32:
      return 'F';
    default:
      return 'D';
  }
}

bool IsInteger(X3pDataType type) { return type == X3pDataType::kInt16 || type == X3pDataType::kInt32; }

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S+00:00", &utc);
  return text;
}

void CheckMap(const HeightMap& map) {
  if (map.size_x < 1 || map.size_y < 1 ||
      map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y) ||
      !(map.dx_mm > 0.0) || !(map.dy_mm > 0.0) || !std::isfinite(map.dx_mm) || !std::isfinite(map.dy_mm)) {
    throw std::invalid_argument("X3P writer: the height map is malformed (sizes, spacing or point count)");
  }
}

pugi::xml_node Add(pugi::xml_node parent, const char* tag, const std::string& text) {
  pugi::xml_node node = parent.append_child(tag);
  node.text().set(text.c_str());
  return node;
}

void AddAxis(pugi::xml_node axes, const char* tag, char axis_type, char data_type, double increment, double offset) {
  pugi::xml_node axis = axes.append_child(tag);
  Add(axis, "AxisType", std::string(1, axis_type));
  Add(axis, "DataType", std::string(1, data_type));
  Add(axis, "Increment", FormatShortest(increment));
  Add(axis, "Offset", FormatShortest(offset));
}

}  // namespace

void X3pWriteOptions::Check() const {
  if (IsInteger(z_type) && !(z_increment_mm > 0.0 && std::isfinite(z_increment_mm))) {
    throw InputError("X3P: integer heights (I, L) need a positive z increment in mm, e.g. 1e-6 for 1 nm steps");
  }
}

namespace {

// The metres to write for a height of z_mm: the double the reader's z_m * 1000 turns back into z_mm exactly when
// one exists (z / 1000 or a neighbour of it; for about 98 % of doubles), else the nearest, one ulp away.
double MetresReadingBackAs(double z_mm) {
  const double z_m = z_mm / kMmPerMetre;
  for (const double candidate : {z_m, std::nextafter(z_m, -INFINITY), std::nextafter(z_m, INFINITY)}) {
    if (candidate * kMmPerMetre == z_mm) return candidate;
  }
  return z_m;
}

}  // namespace

// The heights of `map` as an X3P of options.z_type holds them: metres for F and D, counts of the increment for I
// and L (refused beyond the type's range); valid[i] false where the height is not finite.
X3pPoints X3pFileValues(const HeightMap& map, const X3pWriteOptions& options) {
  const std::size_t n = map.z_mm.size();
  const char code = TypeCode(options.z_type);
  std::vector<bool> valid(n);
  std::vector<double> value(n, 0.0);
  std::int64_t lowest = 0, highest = 0;
  if (options.z_type == X3pDataType::kInt16) lowest = INT16_MIN, highest = INT16_MAX;
  if (options.z_type == X3pDataType::kInt32) lowest = INT32_MIN, highest = INT32_MAX;
  for (std::size_t i = 0; i < n; ++i) {
    valid[i] = std::isfinite(map.z_mm[i]);
    if (!valid[i]) continue;
    const double z_m = MetresReadingBackAs(map.z_mm[i]);
    if (IsInteger(options.z_type)) {
      const double steps = std::round(static_cast<double>(map.z_mm[i]) / options.z_increment_mm);
      if (steps < static_cast<double>(lowest) || steps > static_cast<double>(highest)) {
        throw InputError("X3P: height " + FormatShortest(map.z_mm[i]) + " mm is " + FormatShortest(steps) +
                         " steps of " + FormatShortest(options.z_increment_mm) + " mm, beyond the range of type " +
                         std::string(1, code) + "; choose a larger increment or type L, F or D");
      }
      value[i] = steps;
    } else {
      value[i] = z_m;
    }
  }
  return {std::move(value), std::move(valid)};
}

std::string BuildX3p(const HeightMap& map, const X3pWriteOptions& options) {
  options.Check();
  CheckMap(map);
  const std::size_t n = map.z_mm.size();
  const char code = TypeCode(options.z_type);
  const double z_increment_m = IsInteger(options.z_type) ? options.z_increment_mm / kMmPerMetre : 1.0;

  // Heights as the file holds them: metres for F and D, counts of the increment for I and L.
  const X3pPoints points = X3pFileValues(map, options);
  const std::vector<double>& value = points.raw;
  const std::vector<bool>& valid = points.valid;
  const bool any_invalid = std::find(valid.begin(), valid.end(), false) != valid.end();

  std::string data;
  std::string bits;
  if (options.binary) {
    data.reserve(n * X3pTypeSize(code));
    for (std::size_t i = 0; i < n; ++i) {
      switch (options.z_type) {
        case X3pDataType::kInt16:
          AppendBytes(data, static_cast<std::int16_t>(value[i]));
          break;
        case X3pDataType::kInt32:
          AppendBytes(data, static_cast<std::int32_t>(value[i]));
          break;
        case X3pDataType::kFloat32:
          AppendBytes(data, valid[i] ? static_cast<float>(value[i]) : std::numeric_limits<float>::quiet_NaN());
          break;
        default:
          AppendBytes(data, valid[i] ? value[i] : std::numeric_limits<double>::quiet_NaN());
          break;
      }
    }
    if (any_invalid) {
      bits.assign((n + 7) / 8, '\0');
      for (std::size_t i = 0; i < n; ++i) {
        if (valid[i]) bits[i / 8] = static_cast<char>(static_cast<unsigned char>(bits[i / 8]) | (1u << (i % 8)));
      }
    }
  }

  pugi::xml_document document;
  pugi::xml_node declaration = document.append_child(pugi::node_declaration);
  declaration.append_attribute("version") = "1.0";
  declaration.append_attribute("encoding") = "UTF-8";
  declaration.append_attribute("standalone") = "no";
  pugi::xml_node root = document.append_child("p:ISO5436_2");
  root.append_attribute("xmlns:p") = kNamespace;
  root.append_attribute("xmlns:xsi") = "http://www.w3.org/2001/XMLSchema-instance";
  root.append_attribute("xsi:schemaLocation") =
      "http://www.opengps.eu/2008/ISO5436_2 http://www.opengps.eu/2008/ISO5436_2/ISO5436_2_XML.xsd";

  pugi::xml_node record1 = root.append_child("Record1");
  Add(record1, "Revision", "ISO5436 - 2000");
  Add(record1, "FeatureType", "SUR");
  pugi::xml_node axes = record1.append_child("Axes");
  AddAxis(axes, "CX", 'I', 'D', map.dx_mm / kMmPerMetre, map.x0_mm / kMmPerMetre);
  AddAxis(axes, "CY", 'I', 'D', map.dy_mm / kMmPerMetre, map.y0_mm / kMmPerMetre);
  AddAxis(axes, "CZ", 'A', code, z_increment_m, 0.0);

  const std::string date = options.date.empty() ? UtcNow() : options.date;
  pugi::xml_node record2 = root.append_child("Record2");
  Add(record2, "Date", date);
  Add(record2, "Creator", options.creator);
  pugi::xml_node instrument = record2.append_child("Instrument");
  Add(instrument, "Manufacturer", options.manufacturer);
  Add(instrument, "Model", options.model);
  Add(instrument, "Serial", "not available");
  Add(instrument, "Version", "not available");
  Add(record2, "CalibrationDate", date);
  pugi::xml_node probing = record2.append_child("ProbingSystem");
  Add(probing, "Type", "NonContacting");
  Add(probing, "Identification", "focus variation");
  if (!options.comment.empty()) Add(record2, "Comment", options.comment);

  pugi::xml_node record3 = root.append_child("Record3");
  pugi::xml_node dimension = record3.append_child("MatrixDimension");
  Add(dimension, "SizeX", std::to_string(map.size_x));
  Add(dimension, "SizeY", std::to_string(map.size_y));
  Add(dimension, "SizeZ", "1");
  if (options.binary) {
    pugi::xml_node link = record3.append_child("DataLink");
    Add(link, "PointDataLink", kDataBin);
    Add(link, "MD5ChecksumPointData", Md5Hex(data));
    if (!bits.empty()) {
      Add(link, "ValidPointsLink", kValidBin);
      Add(link, "MD5ChecksumValidPoints", Md5Hex(bits));
    }
  } else {
    pugi::xml_node list = record3.append_child("DataList");
    for (std::size_t i = 0; i < n; ++i) {
      pugi::xml_node datum = list.append_child("Datum");
      if (!valid[i]) continue;  // empty: an invalid point
      if (IsInteger(options.z_type)) {
        datum.text().set(std::to_string(static_cast<std::int64_t>(value[i])).c_str());
      } else if (options.z_type == X3pDataType::kFloat32) {
        datum.text().set(FormatShortest(static_cast<float>(value[i])).c_str());
      } else {
        datum.text().set(FormatShortest(value[i]).c_str());
      }
    }
  }
  pugi::xml_node record4 = root.append_child("Record4");
  Add(record4, "ChecksumFile", kX3pChecksumFile);

  std::ostringstream xml;
  document.save(xml, "  ", pugi::format_default, pugi::encoding_utf8);
  std::vector<ZipEntry> entries;
  entries.push_back({kX3pMainXml, xml.str()});
  entries.push_back({kX3pChecksumFile, Md5Hex(entries.front().content) + " *main.xml\n"});
  if (options.binary) {
    entries.push_back({kDataBin, std::move(data)});
    if (!bits.empty()) entries.push_back({kValidBin, std::move(bits)});
  }
  return BuildZip(entries);
}

void WriteX3p(const std::filesystem::path& path, const HeightMap& map, const X3pWriteOptions& options) {
  WriteFileAtomically(path, BuildX3p(map, options));
}

}  // namespace fvm::imaging
