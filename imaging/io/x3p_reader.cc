// Reading X3P files (imaging/io/x3p.h): the archive's main.xml (x3p_archive.h finds it), its axes and matrix, the
// heights inline or linked, and every checksum the file carries.

#include "imaging/io/x3p.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <pugixml.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/md5.h"
#include "imaging/io/reader_support.h"
#include "imaging/io/x3p_archive.h"
#include "imaging/io/x3p_format.h"
#include "imaging/io/zip_archive.h"

namespace fvm::imaging {
namespace {

constexpr std::size_t kMaxXmlBytes = std::size_t{1} << 31;
constexpr const char* kX3pReexport = "the file is damaged or was edited: export it from the instrument again";

// ---------------------------------------------------------------------------------------------------------------
// Reading

std::string_view LocalName(const pugi::xml_node& node) {
  const std::string_view full = node.name();
  const size_t colon = full.find(':');
  return colon == std::string_view::npos ? full : full.substr(colon + 1);
}

// Records are unqualified in the schema, but some writers prefix them: match local names.
pugi::xml_node Child(const pugi::xml_node& parent, std::string_view local) {
  for (pugi::xml_node child = parent.first_child(); child; child = child.next_sibling()) {
    if (child.type() == pugi::node_element && LocalName(child) == local) return child;
  }
  return {};
}

pugi::xml_node Required(const std::string& name, const pugi::xml_node& parent, std::string_view local,
                        const std::string& where) {
  const pugi::xml_node child = Child(parent, local);
  if (!child) {
    FailReading(name, "main.xml has no <" + where + "/" + std::string(local) +
                          ">, which every X3P surface has (ISO 25178-72); " + kX3pReexport);
  }
  return child;
}

std::string_view Text(const pugi::xml_node& node) { return TrimBlanks(node.text().get()); }

double RequiredNumber(const std::string& name, const pugi::xml_node& parent, std::string_view local,
                      const std::string& where) {
  const pugi::xml_node node = Required(name, parent, local, where);
  const std::optional<double> value = ParseDouble(Text(node));
  if (!value || !std::isfinite(*value)) {
    FailReading(name, "main.xml <" + where + "/" + std::string(local) + "> is '" + std::string(Text(node)) +
                          "', not a finite number; " + kX3pReexport);
  }
  return *value;
}

std::uint64_t RequiredCount(const std::string& name, const pugi::xml_node& parent, std::string_view local) {
  const pugi::xml_node node = Required(name, parent, local, "Record3/MatrixDimension");
  const std::optional<std::int64_t> value = ParseInt(Text(node));
  if (!value || *value < 1 || static_cast<std::uint64_t>(*value) > kMaxPoints) {
    FailReading(name, "main.xml <MatrixDimension/" + std::string(local) + "> is '" + std::string(Text(node)) +
                          "', not a point count between 1 and " + std::to_string(kMaxPoints) + "; " + kX3pReexport);
  }
  return static_cast<std::uint64_t>(*value);
}

struct Axis {
  char type = 'I';     // I incremental, A absolute
  char data_type = 0;  // I, L, F, D; 0 when not given
  double increment = 1.0;
  double offset = 0.0;
};

// An optional element present but empty (<Offset/>) is read as absent, with a note.
bool X3pElementGiven(const pugi::xml_node& node, const std::string& where, std::vector<std::string>& notes) {
  if (!node) return false;
  if (!Text(node).empty()) return true;
  notes.push_back("main.xml <" + where + "/" + node.name() + "> is empty; read as absent (its default)");
  return false;
}

Axis ParseAxis(const std::string& name, const pugi::xml_node& axes, std::string_view local,
               std::vector<std::string>& notes) {
  const std::string where = "Record1/Axes/" + std::string(local);
  const pugi::xml_node node = Required(name, axes, local, "Record1/Axes");
  Axis axis;
  const std::string_view type = Text(Required(name, node, "AxisType", where));
  if (type != "I" && type != "A") {
    FailReading(name, "main.xml <" + where + "/AxisType> is '" + std::string(type) + "', not I or A; " + kX3pReexport);
  }
  axis.type = type.front();
  if (const pugi::xml_node data_type = Child(node, "DataType"); X3pElementGiven(data_type, where, notes)) {
    const std::string_view code = Text(data_type);
    if (code.size() != 1 || std::string_view("ILFD").find(code.front()) == std::string_view::npos) {
      FailReading(name, "main.xml <" + where + "/DataType> is '" + std::string(code) +
                            "', not one of I (int16), L (int32), F (float32), D (float64); " + kX3pReexport);
    }
    axis.data_type = code.front();
  }
  if (X3pElementGiven(Child(node, "Increment"), where, notes)) {
    axis.increment = RequiredNumber(name, node, "Increment", where);
  }
  if (X3pElementGiven(Child(node, "Offset"), where, notes)) axis.offset = RequiredNumber(name, node, "Offset", where);
  if (axis.increment == 0.0 || (axis.type == 'I' && axis.increment < 0.0)) {
    FailReading(name, "main.xml <" + where + "/Increment> is " + FormatShortest(axis.increment) +
                          "; a grid needs a positive spacing; " + kX3pReexport);
  }
  return axis;
}


bool IsMd5(std::string_view text) {
  return text.size() == 32 && text.find_first_not_of("0123456789abcdefABCDEF") == std::string_view::npos;
}

// `what` names the checked content, `where` the place the expected digest came from.
void VerifyMd5(const std::string& name, std::string_view content, std::string_view expected, const std::string& what,
               const std::string& where) {
  expected = TrimBlanks(expected);
  if (!IsMd5(expected)) {
    FailReading(name, where + " holds '" + std::string(expected.substr(0, 40)) + "', not an MD5 digest of " + what +
                          "; " + kX3pReexport);
  }
  const std::string actual = Md5Hex(content);
  if (AsciiLower(expected) != actual) {
    FailReading(name, what + " does not match its MD5 checksum (" + where + " says " + AsciiLower(expected) +
                          ", the content has " + actual + "); " + kX3pReexport);
  }
}

void VerifyChecksumFile(const std::string& name, const ZipReader& zip, const std::string& checksum_file,
                        const std::string& xml) {
  const std::string text = zip.Read(checksum_file, 4096);
  // md5sum's format: the digest, then " *main.xml" (or nothing after it in some writers).
  const std::string_view trimmed = TrimBlanks(text);
  const std::string_view digest = trimmed.substr(0, trimmed.find_first_of(" \t*\r\n"));
  VerifyMd5(name, xml, digest, std::string(kX3pMainXml), checksum_file);
}

std::string Describe(const pugi::xml_node& root) {
  std::string source = "X3P (ISO 25178-72)";
  const pugi::xml_node record2 = Child(root, "Record2");
  if (!record2) return source;
  const pugi::xml_node instrument = Child(record2, "Instrument");
  std::string who;
  for (const char* field : {"Manufacturer", "Model"}) {
    const std::string_view text = Text(Child(instrument, field));
    if (text.empty() || text == "unknown") continue;
    if (!who.empty()) who += ' ';
    who += text;
  }
  if (!who.empty()) source.append(", ").append(who);
  if (const std::string_view date = Text(Child(record2, "Date")); !date.empty()) source.append(", ").append(date);
  return source;
}

}  // namespace

// The heights of a <DataLink>: the binary point file (and the validity bits, when linked), sizes and MD5 sums
// checked against main.xml.
X3pPoints ReadX3pLinkedPoints(const std::string& name, const ZipReader& zip, const X3pArchiveLayout& layout,
                              const pugi::xml_node link, const Axis& cz, std::size_t n, const std::string& points_said,
                              std::vector<std::string>& notes) {
  std::vector<double> raw;
  std::vector<bool> valid;
  const std::string data_file =
      layout.Entry(zip, std::string(Text(Required(name, link, "PointDataLink", "Record3/DataLink"))));
  if (!zip.Has(data_file))
    FailReading(name, "main.xml links point data '" + data_file + "', which the archive lacks");
  const std::size_t type_size = X3pTypeSize(cz.data_type);
  const std::size_t expected = n * type_size;
  if (zip.DeclaredSize(data_file) != expected) {
    FailReading(name, points_said + " of type " + std::string(1, cz.data_type) + " (" + std::to_string(expected) +
                          " bytes), but " + data_file + " holds " + std::to_string(zip.DeclaredSize(data_file)) +
                          " bytes; " + kX3pReexport);
  }
  const std::string data = zip.Read(data_file, expected);
  if (const pugi::xml_node md5 = Child(link, "MD5ChecksumPointData");
      X3pElementGiven(md5, "Record3/DataLink", notes)) {
    VerifyMd5(name, data, Text(md5), data_file, "main.xml <MD5ChecksumPointData>");
  }
  raw.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* p = data.data() + i * type_size;
    switch (cz.data_type) {
      case 'I':
        raw[i] = LoadBytes<std::int16_t>(p);
        break;
      case 'L':
        raw[i] = LoadBytes<std::int32_t>(p);
        break;
      case 'F':
        raw[i] = LoadBytes<float>(p);
        break;
      default:
        raw[i] = LoadBytes<double>(p);
        break;
    }
  }
  if (const pugi::xml_node valid_link = Child(link, "ValidPointsLink");
      X3pElementGiven(valid_link, "Record3/DataLink", notes)) {
    const std::string valid_file = layout.Entry(zip, std::string(Text(valid_link)));
    if (!zip.Has(valid_file))
      FailReading(name, "main.xml links validity bits '" + valid_file + "', which the archive lacks");
    const std::size_t needed = (n + 7) / 8;
    const std::size_t declared = zip.DeclaredSize(valid_file);
    // A few writers pad the bit file; more than twice the size it needs is a lie about the sizes.
    if (declared < needed || declared > 2 * needed + 64) {
      FailReading(name, points_said + " (" + std::to_string(needed) + " bytes of validity bits), but " + valid_file +
                            " holds " + std::to_string(declared) + " bytes; " + kX3pReexport);
    }
    const std::string bits = zip.Read(valid_file, declared);
    if (const pugi::xml_node md5 = Child(link, "MD5ChecksumValidPoints");
        X3pElementGiven(md5, "Record3/DataLink", notes)) {
      VerifyMd5(name, bits, Text(md5), valid_file, "main.xml <MD5ChecksumValidPoints>");
    }
    valid.resize(n);
    // Point i is bit (i % 8) of byte i / 8, least significant bit first.
    for (std::size_t i = 0; i < n; ++i) valid[i] = (static_cast<unsigned char>(bits[i / 8]) >> (i % 8)) & 1u;
  }
  return {std::move(raw), std::move(valid)};
}

// The heights of a <DataList>: one <Datum> per point, empty for an invalid one.
std::vector<double> ReadX3pDataList(const std::string& name, const pugi::xml_node list, std::size_t n,
                                    const std::string& points_said) {
  std::vector<double> raw;
  std::size_t count = 0;
  for (pugi::xml_node datum = list.first_child(); datum; datum = datum.next_sibling()) {
    if (datum.type() == pugi::node_element && LocalName(datum) == "Datum") ++count;
  }
  if (count != n) {
    FailReading(name, points_said + ", but its DataList holds " + std::to_string(count) + " <Datum> elements; " +
                          kX3pReexport);
  }
  raw.resize(n);
  std::size_t i = 0;
  for (pugi::xml_node datum = list.first_child(); datum; datum = datum.next_sibling()) {
    if (datum.type() != pugi::node_element || LocalName(datum) != "Datum") continue;
    const std::string_view text = Text(datum);
    if (text.empty()) {  // an empty Datum is an invalid point
      raw[i++] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    const std::optional<double> value = ParseDouble(text);
    if (!value) {
      FailReading(name, "main.xml <Datum> " + std::to_string(i + 1) + " is '" + std::string(text.substr(0, 40)) +
                            "', not a number; " + kX3pReexport);
    }
    raw[i++] = *value;
  }
  return raw;
}

HeightMap ParseX3p(std::string bytes, const std::string& name) {
  const ZipReader zip(std::move(bytes), name);
  const X3pArchiveLayout layout = LocateX3pMainXml(zip, name);
  std::vector<std::string> notes = layout.notes;
  const std::string xml = zip.Read(layout.folder + kX3pMainXml, kMaxXmlBytes);
  // Before parsing: a damaged main.xml is better reported as a checksum failure than as an XML error.
  if (zip.Has(layout.Entry(zip, kX3pChecksumFile))) VerifyChecksumFile(name, zip, layout.Entry(zip, kX3pChecksumFile), xml);

  pugi::xml_document document;
  const pugi::xml_parse_result parsed = document.load_buffer(xml.data(), xml.size());
  if (!parsed) {
    FailReading(name, std::string("main.xml is not well-formed XML (") + parsed.description() + " at byte " +
                          std::to_string(parsed.offset) + "); " + kX3pReexport);
  }
  const pugi::xml_node root = document.document_element();
  if (LocalName(root) != "ISO5436_2") {
    FailReading(name, "main.xml has root <" + std::string(root.name()) + ">, not <ISO5436_2>: not an X3P file");
  }
  if (const pugi::xml_node record4 = Child(root, "Record4")) {
    const std::string checksum_file(Text(Child(record4, "ChecksumFile")));
    if (!checksum_file.empty() && checksum_file != kX3pChecksumFile && zip.Has(layout.Entry(zip, checksum_file))) {
      VerifyChecksumFile(name, zip, layout.Entry(zip, checksum_file), xml);
    }
  }
  for (std::string& note : X3pDocumentNotes(root, zip, layout)) notes.push_back(std::move(note));

  const pugi::xml_node record1 = Required(name, root, "Record1", "ISO5436_2");
  const std::string feature(Text(Child(record1, "FeatureType")));
  if (!feature.empty() && feature != "SUR" && feature != "PRF") {
    FailReading(name,
                "holds FeatureType " + feature +
                    " (a point cloud); fvm reads X3P surfaces on a grid (SUR, PRF): export the surface as a grid, "
                    "or as PLY/PCD for a point cloud");
  }
  const pugi::xml_node axes = Required(name, record1, "Axes", "Record1");
  const Axis cx = ParseAxis(name, axes, "CX", notes);
  const Axis cy = ParseAxis(name, axes, "CY", notes);
  const Axis cz = ParseAxis(name, axes, "CZ", notes);
  if (cx.type != 'I' || cy.type != 'I') {
    FailReading(name,
                "has absolute X/Y axes (a list of x, y, z points); fvm reads X3P surfaces on a regular grid "
                "(AxisType I for CX and CY): export the surface on a grid");
  }
  if (cz.type != 'A') FailReading(name, "main.xml <Record1/Axes/CZ/AxisType> is I; heights need an absolute axis (A)");
  if (cz.data_type == 0) {
    FailReading(name, "main.xml <Record1/Axes/CZ> has no DataType (I, L, F or D), so its heights cannot be decoded; " +
                          std::string(kX3pReexport));
  }

  const pugi::xml_node record3 = Required(name, root, "Record3", "ISO5436_2");
  const pugi::xml_node dimension = Required(name, record3, "MatrixDimension", "Record3");
  const std::uint64_t size_x = RequiredCount(name, dimension, "SizeX");
  const std::uint64_t size_y = RequiredCount(name, dimension, "SizeY");
  const std::uint64_t size_z = RequiredCount(name, dimension, "SizeZ");
  if (size_z != 1) {
    FailReading(name, "has SizeZ " + std::to_string(size_z) + " (several layers); fvm reads single-layer surfaces");
  }
  if (size_x * size_y > kMaxPoints) {
    FailReading(name, "main.xml says " + std::to_string(size_x) + " x " + std::to_string(size_y) +
                          " points, more than fvm can hold (" + std::to_string(kMaxPoints) + ")");
  }
  const std::size_t n = static_cast<std::size_t>(size_x * size_y);
  const std::string points_said = "MatrixDimension says " + std::to_string(size_x) + " x " + std::to_string(size_y) +
                                  " = " + std::to_string(n) + " points";

  X3pPoints points;
  if (const pugi::xml_node link = Child(record3, "DataLink")) {
    points = ReadX3pLinkedPoints(name, zip, layout, link, cz, n, points_said, notes);
  } else if (const pugi::xml_node list = Child(record3, "DataList")) {
    points.raw = ReadX3pDataList(name, list, n, points_said);
  } else {
    FailReading(name, "main.xml <Record3> has neither a DataLink nor a DataList: the file holds no heights; " +
                          std::string(kX3pReexport));
  }

  HeightMap map;
  map.size_x = static_cast<int>(size_x);
  map.size_y = static_cast<int>(size_y);
  map.dx_mm = cx.increment * kMmPerMetre;
  map.dy_mm = cy.increment * kMmPerMetre;
  map.x0_mm = cx.offset * kMmPerMetre;
  map.y0_mm = cy.offset * kMmPerMetre;
  map.source = Describe(root);
  map.notes = std::move(notes);
  map.z_mm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // [ISO 5436-2] scales every type the same way; floats usually carry increment 1 and offset 0.
    const double z_m = cz.offset + cz.increment * points.raw[i];
    const bool ok = (points.valid.empty() || points.valid[i]) && std::isfinite(z_m);
    map.z_mm[i] = ok ? z_m * kMmPerMetre : std::numeric_limits<double>::quiet_NaN();
  }
  return map;
}

HeightMap ReadX3p(const std::filesystem::path& path) { return ParseX3p(ReadFileBytes(path), path.string()); }

}  // namespace fvm::imaging
