#include "imaging/io/pcd_file.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

// An LZF back reference of 3 bytes copies at most 264 bytes: no body expands more than that.
constexpr std::uint64_t kMaxLzfExpansion = 88;

const char* const kPcdRewrite = "; the file is damaged or not PCD: export it again";

struct Field {
  std::string name;
  char type = 'F';  // F, I or U
  std::uint64_t size = 4;
  std::uint64_t count = 1;
};

struct PcdHeader {
  std::vector<Field> fields;
  std::uint64_t width = 0, height = 0;
  std::string data;           // ascii, binary or binary_compressed
  std::size_t body = 0;       // first byte after the DATA line
  std::size_t body_line = 0;  // line number of the first data row
};

std::uint64_t CountOf(std::string_view word, const std::string& where, const std::string& what) {
  const std::optional<std::int64_t> value = ParseInt(word);
  if (!value || *value < 0) FailReading(where, what + " is " + QuotedForMessage(word) + ", not a count" + kPcdRewrite);
  return static_cast<std::uint64_t>(*value);
}

PcdHeader ReadPcdHeader(std::string_view bytes, const std::string& name) {
  PcdHeader header;
  std::vector<std::string_view> fields, sizes, types, counts;
  std::optional<std::uint64_t> width, height, points;
  bool version = false;
  std::size_t start = 0, line_number = 0;
  while (true) {
    const size_t newline = bytes.find('\n', start);
    if (newline == std::string_view::npos) {
      FailReading(name, "its PCD header does not end with a DATA line" + std::string(kPcdRewrite));
    }
    const std::string_view line = bytes.substr(start, newline - start);
    start = newline + 1;
    ++line_number;
    const std::string where = name + ":" + std::to_string(line_number);
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.empty() || words[0].front() == '#') continue;
    const std::string key = AsciiLower(words[0]);
    const std::vector<std::string_view> values(words.begin() + 1, words.end());
    if (!version && key != "version") {
      FailReading(where, "a PCD header starts with VERSION, not " + QuotedForMessage(words[0]) + kPcdRewrite);
    }
    const auto one = [&]() {
      if (values.size() != 1)
        FailReading(where, key + " takes one value, not " + std::to_string(values.size()) + kPcdRewrite);
      return values[0];
    };
    const auto once = [&](bool seen) {
      if (seen) FailReading(where, "a second " + key + " line" + kPcdRewrite);
    };
    if (key == "version") {
      once(version);
      one();
      version = true;
    } else if (key == "fields") {
      once(!fields.empty());
      fields = values;
      if (fields.empty()) FailReading(where, "FIELDS names no field" + std::string(kPcdRewrite));
    } else if (key == "size") {
      once(!sizes.empty());
      sizes = values;
    } else if (key == "type") {
      once(!types.empty());
      types = values;
    } else if (key == "count") {
      once(!counts.empty());
      counts = values;
    } else if (key == "width") {
      once(width.has_value());
      width = CountOf(one(), where, "WIDTH");
    } else if (key == "height") {
      once(height.has_value());
      height = CountOf(one(), where, "HEIGHT");
    } else if (key == "points") {
      once(points.has_value());
      points = CountOf(one(), where, "POINTS");
    } else if (key == "viewpoint") {
      if (values.size() != 7) FailReading(where, "VIEWPOINT takes 7 numbers" + std::string(kPcdRewrite));
    } else if (key == "data") {
      header.data = AsciiLower(one());
      if (header.data != "ascii" && header.data != "binary" && header.data != "binary_compressed") {
        FailReading(
            where, "DATA is " + QuotedForMessage(values[0]) + ", not ascii, binary or binary_compressed" + kPcdRewrite);
      }
      header.body = start;
      header.body_line = line_number + 1;
      break;
    } else {
      FailReading(where, "unknown PCD header line " + QuotedForMessage(words[0]) + kPcdRewrite);
    }
  }
  const std::string where = name + ": its PCD header";
  if (fields.empty()) FailReading(where, " has no FIELDS line" + std::string(kPcdRewrite));
  if (counts.empty()) counts.assign(fields.size(), "1");  // COUNT is optional: one value per field
  if (sizes.size() != fields.size() || types.size() != fields.size() || counts.size() != fields.size()) {
    FailReading(where, " gives " + std::to_string(sizes.size()) + " SIZE, " + std::to_string(types.size()) +
                           " TYPE and " + std::to_string(counts.size()) + " COUNT values for " +
                           std::to_string(fields.size()) + " FIELDS; it needs one of each per field" + kPcdRewrite);
  }
  if (!width || !height) FailReading(where, " has no WIDTH or no HEIGHT line" + std::string(kPcdRewrite));
  if (!points) FailReading(where, " has no POINTS line" + std::string(kPcdRewrite));
  for (size_t i = 0; i < fields.size(); ++i) {
    Field field;
    field.name = std::string(fields[i]);
    const std::string type = AsciiLower(types[i]);
    field.type = type.size() == 1 ? static_cast<char>(std::toupper(static_cast<unsigned char>(type[0]))) : '?';
    field.size = CountOf(sizes[i], where, "the SIZE of field '" + field.name + "'");
    field.count = CountOf(counts[i], where, "the COUNT of field '" + field.name + "'");
    const bool integer = field.type == 'I' || field.type == 'U';
    const bool valid = integer ? (field.size == 1 || field.size == 2 || field.size == 4 || field.size == 8)
                               : field.type == 'F' && (field.size == 4 || field.size == 8);
    if (!valid) {
      FailReading(where, "'s field '" + field.name + "' has TYPE " + QuotedForMessage(types[i]) + " and SIZE " +
                             QuotedForMessage(sizes[i]) + "; PCD knows F 4, F 8 and I or U 1, 2, 4, 8" + kPcdRewrite);
    }
    if (field.count < 1 || field.count > 1000000) {
      FailReading(where, "'s field '" + field.name + "' has COUNT " + QuotedForMessage(counts[i]) + kPcdRewrite);
    }
    header.fields.push_back(field);
  }
  if (*width > kMaxPoints || *height > kMaxPoints || *width * *height > kMaxPoints) {
    FailReading(where, " declares more points than fvm can hold" + std::string(kPcdRewrite));
  }
  if (*points != *width * *height) {
    FailReading(where, " declares POINTS " + std::to_string(*points) + " but WIDTH x HEIGHT " + std::to_string(*width) +
                           " x " + std::to_string(*height) + kPcdRewrite);
  }
  if (*points == 0) FailReading(name, "holds no points; export the cloud again");
  header.width = *width;
  header.height = *height;
  return header;
}

// Where x, y and z are among the fields.
std::array<size_t, 3> CoordinateFields(const PcdHeader& header, const std::string& name) {
  std::array<size_t, 3> index{};
  for (int axis = 0; axis < 3; ++axis) {
    const std::string wanted(1, static_cast<char>('x' + axis));
    size_t found = header.fields.size();
    for (size_t i = 0; i < header.fields.size(); ++i) {
      if (header.fields[i].name != wanted) continue;
      if (found != header.fields.size()) FailReading(name, "names field '" + wanted + "' twice" + kPcdRewrite);
      found = i;
    }
    if (found == header.fields.size()) {
      FailReading(name, "has no '" + wanted + "' field; fvm reads clouds of x, y, z points");
    }
    if (header.fields[found].count != 1) {
      FailReading(name, "its field '" + wanted + "' has COUNT " + std::to_string(header.fields[found].count) +
                            ": a coordinate is one value per point" + kPcdRewrite);
    }
    index[static_cast<size_t>(axis)] = found;
  }
  return index;
}

double Load(const unsigned char* p, const Field& field) {
  const auto load = [p](auto value) {
    std::memcpy(&value, p, sizeof value);
    return static_cast<double>(value);
  };
  switch (field.type) {
    case 'F':
      return field.size == 4 ? load(float{}) : load(double{});
    case 'I':
      return field.size == 1 ? load(std::int8_t{})
             : field.size == 2 ? load(std::int16_t{})
             : field.size == 4 ? load(std::int32_t{})
                               : load(std::int64_t{});
    default:
      return field.size == 1 ? load(std::uint8_t{})
             : field.size == 2 ? load(std::uint16_t{})
             : field.size == 4 ? load(std::uint32_t{})
                               : load(std::uint64_t{});
  }
}

// liblzf's format, every read and write bounds-checked. Throws unless `in` expands to exactly `out.size()`.
void DecompressLzf(std::string_view in, std::vector<unsigned char>& out, const std::string& name) {
  const std::string bad = "its LZF-compressed body is damaged" + std::string(kPcdRewrite);
  size_t ip = 0, op = 0;
  while (ip < in.size()) {
    const unsigned ctrl = static_cast<unsigned char>(in[ip++]);
    if (ctrl < 32) {  // a literal run of ctrl + 1 bytes
      const size_t length = ctrl + 1;
      if (length > in.size() - ip || length > out.size() - op) FailReading(name, bad);
      std::memcpy(out.data() + op, in.data() + ip, length);
      ip += length;
      op += length;
    } else {  // a back reference
      size_t length = ctrl >> 5;
      size_t distance = (ctrl & 0x1fu) << 8;
      if (ip >= in.size()) FailReading(name, bad);
      if (length == 7) {
        length += static_cast<unsigned char>(in[ip++]);
        if (ip >= in.size()) FailReading(name, bad);
      }
      distance += static_cast<unsigned char>(in[ip++]) + 1u;
      length += 2;
      if (distance > op || length > out.size() - op) FailReading(name, bad);
      for (size_t i = 0; i < length; ++i, ++op) out[op] = out[op - distance];  // may overlap: byte by byte
    }
  }
  if (op != out.size()) FailReading(name, bad);
}

// PCL's writer pads a binary file with zeros to a whole page after the points: zeros after the body are allowed,
// anything else means the header and the body disagree.
bool IsPadding(std::string_view rest) {
  return std::all_of(rest.begin(), rest.end(), [](char c) { return c == '\0'; });
}

std::uint32_t LoadU32(std::string_view bytes, size_t at) {
  std::uint32_t value;
  std::memcpy(&value, bytes.data() + at, sizeof value);
  return value;
}

std::vector<Eigen::Vector3d> ReadAscii(std::string_view bytes, const PcdHeader& header,
                                       const std::array<size_t, 3>& xyz, const std::string& name) {
  std::uint64_t values_per_row = 0;
  for (const Field& field : header.fields) values_per_row += field.count;
  // The first value of each field in a row.
  std::vector<std::uint64_t> first(header.fields.size(), 0);
  for (size_t i = 1; i < header.fields.size(); ++i) first[i] = first[i - 1] + header.fields[i - 1].count;
  const std::uint64_t n = header.width * header.height;
  std::vector<Eigen::Vector3d> points;
  std::size_t start = header.body, line_number = header.body_line - 1;
  while (start < bytes.size()) {
    const size_t end = std::min(bytes.find('\n', start), bytes.size());
    const std::string_view line = bytes.substr(start, end - start);
    start = end + 1;
    ++line_number;
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.empty()) continue;
    const std::string where = name + ":" + std::to_string(line_number);
    if (points.size() == n) {
      FailReading(where, "more rows than the header's POINTS " + std::to_string(n) + kPcdRewrite);
    }
    if (words.size() != values_per_row) {
      FailReading(where, std::to_string(words.size()) + " values where the header's FIELDS and COUNT declare " +
                             std::to_string(values_per_row) + kPcdRewrite);
    }
    for (const std::string_view word : words) {
      if (!ParseDouble(word)) FailReading(where, QuotedForMessage(word) + " is not a number" + kPcdRewrite);
    }
    Eigen::Vector3d p;
    for (int axis = 0; axis < 3; ++axis) {
      const size_t field = xyz[static_cast<size_t>(axis)];
      double value = *ParseDouble(words[first[field]]);
      // The file's precision, as a binary file of the same fields would hold it.
      // (Beyond float's range the value stays as written: the conversion would be undefined.)
      if (header.fields[field].type == 'F' && header.fields[field].size == 4 &&
          std::abs(value) <= std::numeric_limits<float>::max()) {
        value = static_cast<float>(value);
      }
      p[axis] = value;
    }
    points.push_back(p);
  }
  if (points.size() != n) {
    FailReading(name, "holds " + std::to_string(points.size()) + " data rows where the header declares POINTS " +
                          std::to_string(n) + "; the file is incomplete or damaged: export it again");
  }
  return points;
}

}  // namespace

PointCloud ParsePcd(std::string_view bytes, const std::string& name, double mm_per_unit) {
  const PcdHeader header = ReadPcdHeader(bytes, name);
  const std::array<size_t, 3> xyz = CoordinateFields(header, name);
  const std::uint64_t n = header.width * header.height;
  std::vector<Eigen::Vector3d> points;
  if (header.data == "ascii") {
    points = ReadAscii(bytes, header, xyz, name);
  } else {
    std::uint64_t point_step = 0;
    std::vector<std::uint64_t> offset;  // of each field within a point (binary) or of its block (compressed)
    for (const Field& field : header.fields) {
      offset.push_back(point_step);
      point_step += field.size * field.count;
    }
    if (point_step > (std::uint64_t{1} << 32))
      FailReading(name, "its points are larger than fvm can hold" + std::string(kPcdRewrite));
    const std::uint64_t needed = n * point_step;  // below 2^31 x 2^32: no overflow
    const std::string_view body = bytes.substr(header.body);
    std::string_view data = body;
    std::vector<unsigned char> expanded;
    if (header.data == "binary_compressed") {
      if (body.size() < 8) FailReading(name, "its binary_compressed body has no sizes" + std::string(kPcdRewrite));
      const std::uint64_t compressed = LoadU32(body, 0), uncompressed = LoadU32(body, 4);
      if (compressed > body.size() - 8 || !IsPadding(body.substr(8 + compressed))) {
        FailReading(name, "its binary_compressed body declares " + std::to_string(compressed) +
                              " compressed bytes, but " + std::to_string(body.size() - 8) + " follow" + kPcdRewrite);
      }
      if (uncompressed != needed) {
        FailReading(name, "its binary_compressed body expands to " + std::to_string(uncompressed) +
                              " bytes, but the header's FIELDS, SIZE, COUNT and POINTS need " + std::to_string(needed) +
                              kPcdRewrite);
      }
      if (uncompressed > compressed * kMaxLzfExpansion) {
        FailReading(name, "its binary_compressed body cannot expand to the " + std::to_string(uncompressed) +
                              " bytes it declares" + kPcdRewrite);
      }
      expanded.resize(static_cast<size_t>(uncompressed));
      DecompressLzf(body.substr(8, compressed), expanded, name);
      data = std::string_view(reinterpret_cast<const char*>(expanded.data()), expanded.size());
    } else if (body.size() < needed) {
      FailReading(name, "the header declares " + std::to_string(n) + " points of " + std::to_string(point_step) +
                            " bytes, but the binary body holds " + std::to_string(body.size()) +
                            " bytes; the file is incomplete or damaged: export it again");
    } else if (!IsPadding(body.substr(needed))) {
      FailReading(name, "its binary body holds " + std::to_string(body.size()) +
                            " bytes, but the header's FIELDS, SIZE, " + "COUNT and POINTS need " +
                            std::to_string(needed) + " (and zeros after them)" + kPcdRewrite);
    }
    const bool by_field = header.data == "binary_compressed";  // compressed bodies store field after field
    points.resize(static_cast<size_t>(n));
    const auto* base = reinterpret_cast<const unsigned char*>(data.data());
    for (int axis = 0; axis < 3; ++axis) {
      const Field& field = header.fields[xyz[static_cast<size_t>(axis)]];
      const std::uint64_t at = offset[xyz[static_cast<size_t>(axis)]];
      for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t position = by_field ? at * n + i * field.size : i * point_step + at;
        points[static_cast<size_t>(i)][axis] = Load(base + position, field);
      }
    }
  }
  for (Eigen::Vector3d& p : points) p *= mm_per_unit;
  PointCloud cloud;
  cloud.points = std::move(points);
  cloud.width = static_cast<int>(header.width);
  cloud.height = static_cast<int>(header.height);
  cloud.source = "PCD";
  return cloud;
}

}  // namespace fvm::imaging
