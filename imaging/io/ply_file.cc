#include "imaging/io/ply_file.h"

#include <algorithm>
#include <array>
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

const char* const kPlyRewrite = "; the file is damaged or not PLY: export it again";

enum class Scalar { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<Scalar> ScalarOf(std::string_view word) {
  static const std::pair<const char*, Scalar> kNames[] = {
      {"char", Scalar::kInt8},     {"int8", Scalar::kInt8},       {"uchar", Scalar::kUint8},
      {"uint8", Scalar::kUint8},   {"short", Scalar::kInt16},     {"int16", Scalar::kInt16},
      {"ushort", Scalar::kUint16}, {"uint16", Scalar::kUint16},   {"int", Scalar::kInt32},
      {"int32", Scalar::kInt32},   {"uint", Scalar::kUint32},     {"uint32", Scalar::kUint32},
      {"float", Scalar::kFloat32}, {"float32", Scalar::kFloat32}, {"double", Scalar::kFloat64},
      {"float64", Scalar::kFloat64}};
  for (const auto& [text, scalar] : kNames) {
    if (word == text) return scalar;
  }
  return std::nullopt;
}

std::size_t SizeOf(Scalar scalar) {
  switch (scalar) {
    case Scalar::kInt8:
    case Scalar::kUint8:
      return 1;
    case Scalar::kInt16:
    case Scalar::kUint16:
      return 2;
    case Scalar::kFloat64:
      return 8;
    default:
      return 4;
  }
}

bool IsInteger(Scalar scalar) { return scalar != Scalar::kFloat32 && scalar != Scalar::kFloat64; }

struct Property {
  std::string name;
  Scalar type = Scalar::kFloat32;
  std::optional<Scalar> list_count;  // set for list properties: the type of the length before the items
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { kAscii, kLittle, kBig };

struct PlyHeader {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  std::optional<std::uint64_t> columns, rows;  // obj_info num_cols / num_rows (PCL's organised clouds)
  std::size_t body = 0;
  std::size_t body_line = 0;
};

PlyHeader ReadPlyHeader(std::string_view bytes, const std::string& name) {
  PlyHeader header;
  bool format = false;
  std::size_t start = 0, line_number = 0;
  while (true) {
    const size_t newline = bytes.find('\n', start);
    if (newline == std::string_view::npos)
      FailReading(name, "its PLY header does not end with end_header" + std::string(kPlyRewrite));
    const std::string_view line = bytes.substr(start, newline - start);
    start = newline + 1;
    ++line_number;
    const std::string where = name + ":" + std::to_string(line_number);
    const std::vector<std::string_view> words = SplitWords(line);
    if (line_number == 1) {
      if (words.size() != 1 || words[0] != "ply")
        FailReading(name, "does not start with a 'ply' line" + std::string(kPlyRewrite));
      continue;
    }
    if (words.empty()) FailReading(where, "a blank line in the PLY header" + std::string(kPlyRewrite));
    const std::string_view key = words[0];
    if (key == "comment") continue;
    if (key == "obj_info") {
      if (words.size() == 3 && (words[1] == "num_cols" || words[1] == "num_rows")) {
        const std::optional<std::int64_t> value = ParseInt(words[2]);
        if (value && *value > 0) (words[1] == "num_cols" ? header.columns : header.rows) = *value;
      }
      continue;
    }
    if (key == "format") {
      if (format || words.size() != 3 || words[2] != "1.0")
        FailReading(where, "a malformed format line" + std::string(kPlyRewrite));
      if (words[1] == "ascii") {
        header.encoding = Encoding::kAscii;
      } else if (words[1] == "binary_little_endian") {
        header.encoding = Encoding::kLittle;
      } else if (words[1] == "binary_big_endian") {
        header.encoding = Encoding::kBig;
      } else {
        FailReading(where, "unknown PLY format " + QuotedForMessage(words[1]) + kPlyRewrite);
      }
      format = true;
    } else if (key == "element") {
      const std::optional<std::int64_t> count = words.size() == 3 ? ParseInt(words[2]) : std::nullopt;
      if (!count || *count < 0)
        FailReading(where, "an element line needs a name and a count" + std::string(kPlyRewrite));
      for (const Element& element : header.elements) {
        if (element.name == words[1])
          FailReading(where, "a second element " + QuotedForMessage(words[1]) + kPlyRewrite);
      }
      header.elements.push_back({std::string(words[1]), static_cast<std::uint64_t>(*count), {}});
    } else if (key == "property") {
      if (header.elements.empty()) FailReading(where, "a property before any element" + std::string(kPlyRewrite));
      Property property;
      std::optional<Scalar> type;
      if (words.size() == 3) {
        type = ScalarOf(words[1]);
        property.name = std::string(words[2]);
      } else if (words.size() == 5 && words[1] == "list") {
        property.list_count = ScalarOf(words[2]);
        if (!property.list_count || !IsInteger(*property.list_count)) {
          FailReading(where, "a list length must be of an integer type" + std::string(kPlyRewrite));
        }
        type = ScalarOf(words[3]);
        property.name = std::string(words[4]);
      }
      if (!type)
        FailReading(where, "a malformed property line; PLY has 'property TYPE NAME'" + std::string(kPlyRewrite));
      property.type = *type;
      for (const Property& other : header.elements.back().properties) {
        if (other.name == property.name)
          FailReading(where, "a second property " + QuotedForMessage(property.name) + kPlyRewrite);
      }
      header.elements.back().properties.push_back(property);
    } else if (key == "end_header") {
      if (words.size() != 1) FailReading(where, "a malformed end_header line" + std::string(kPlyRewrite));
      header.body = start;
      header.body_line = line_number + 1;
      break;
    } else {
      FailReading(where, "unknown PLY header line " + QuotedForMessage(key) + kPlyRewrite);
    }
  }
  if (!format) FailReading(name, "its PLY header has no format line" + std::string(kPlyRewrite));
  for (const Element& element : header.elements) {
    if (element.properties.empty() && element.count > 0) {
      FailReading(name,
                  "its PLY element " + QuotedForMessage(element.name) + " has rows but no properties" + kPlyRewrite);
    }
    // Every row takes at least a byte (binary) or a line (ascii).
    if (element.count > bytes.size() - header.body) {
      FailReading(name, "its PLY element " + QuotedForMessage(element.name) + " declares " +
                            std::to_string(element.count) + " rows, more than the file's " +
                            std::to_string(bytes.size()) +
                            " bytes can hold; the file is incomplete or damaged: export it again");
    }
  }
  return header;
}

// Reads the body value by value, in either encoding, and says where it stopped when something is missing.
class Body {
 public:
  Body(std::string_view bytes, const PlyHeader& header, const std::string& name)
      : bytes_(bytes), encoding_(header.encoding), name_(name), at_(header.body), line_number_(header.body_line - 1) {}

  // Starts a row of `element` (ascii: the next non-blank line).
  void StartRow(const Element& element, std::uint64_t row) {
    where_ = name_ + ": element '" + element.name + "' row " + std::to_string(row + 1);
    if (encoding_ != Encoding::kAscii) return;
    words_.clear();
    next_word_ = 0;
    while (words_.empty()) {
      if (at_ >= bytes_.size()) FailReading(where_, "missing: the file ends early; it is incomplete: export it again");
      const size_t end = std::min(bytes_.find('\n', at_), bytes_.size());
      words_ = SplitWords(bytes_.substr(at_, end - at_));
      at_ = end + 1;
      ++line_number_;
    }
    where_ = name_ + ":" + std::to_string(line_number_) + " (element '" + element.name + "' row " +
             std::to_string(row + 1) + ")";
  }

  void EndRow() {
    if (encoding_ == Encoding::kAscii && next_word_ != words_.size()) {
      FailReading(where_,
                  std::to_string(words_.size()) + " values, more than the header's properties declare" + kPlyRewrite);
    }
  }

  double Next(Scalar type) {
    if (encoding_ == Encoding::kAscii) {
      if (next_word_ == words_.size()) {
        FailReading(where_, std::to_string(words_.size()) + " values, fewer than the header's properties declare" +
                                kPlyRewrite);
      }
      const std::string_view word = words_[next_word_++];
      const std::optional<double> value = ParseDouble(word);
      if (!value) FailReading(where_, QuotedForMessage(word) + " is not a number" + kPlyRewrite);
      if (IsInteger(type) && *value != std::floor(*value))
        FailReading(where_, QuotedForMessage(word) + " is not an integer" + kPlyRewrite);
      // A float property holds the float nearest the text; beyond float's range the conversion would be undefined.
      const bool to_float = type == Scalar::kFloat32 && std::abs(*value) <= std::numeric_limits<float>::max();
      return to_float ? static_cast<float>(*value) : *value;
    }
    const std::size_t size = SizeOf(type);
    if (size > bytes_.size() - at_)
      FailReading(where_, "missing: the file ends early; it is incomplete: export it again");
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + at_, size);
    at_ += size;
    if (encoding_ == Encoding::kBig) std::reverse(raw, raw + size);
    const auto load = [&raw](auto value) {
      std::memcpy(&value, raw, sizeof value);
      return static_cast<double>(value);
    };
    switch (type) {
      case Scalar::kInt8:
        return load(std::int8_t{});
      case Scalar::kUint8:
        return load(std::uint8_t{});
      case Scalar::kInt16:
        return load(std::int16_t{});
      case Scalar::kUint16:
        return load(std::uint16_t{});
      case Scalar::kInt32:
        return load(std::int32_t{});
      case Scalar::kUint32:
        return load(std::uint32_t{});
      case Scalar::kFloat32:
        return load(float{});
      default:
        return load(double{});
    }
  }

  // The length of a list: a non-negative integer, no longer than the rest of the file could hold.
  std::uint64_t ListLength(Scalar type) {
    const double length = Next(type);
    const double room = encoding_ == Encoding::kAscii ? static_cast<double>(words_.size() - next_word_)
                                                       : static_cast<double>(bytes_.size() - at_);
    if (length < 0 || length > room) FailReading(where_, "a list length of " + FormatShortest(length) + kPlyRewrite);
    return static_cast<std::uint64_t>(length);
  }

  void CheckEnd() const {
    const std::string_view rest = at_ < bytes_.size() ? bytes_.substr(at_) : std::string_view();
    const bool clean = encoding_ == Encoding::kAscii ? rest.find_first_not_of(" \t\r\n") == std::string_view::npos
                                                     : rest.empty();
    if (!clean) {
      FailReading(name_,
                  std::to_string(rest.size()) + " bytes follow the last element the header declares" + kPlyRewrite);
    }
  }

 private:
  std::string_view bytes_;
  Encoding encoding_;
  std::string name_;
  std::size_t at_;
  std::size_t line_number_;
  std::string where_;
  std::vector<std::string_view> words_;
  std::size_t next_word_ = 0;
};

}  // namespace

PointCloud ParsePly(std::string_view bytes, const std::string& name, double mm_per_unit) {
  const PlyHeader header = ReadPlyHeader(bytes, name);
  const auto vertex_element =
      std::find_if(header.elements.begin(), header.elements.end(), [](const Element& e) { return e.name == "vertex"; });
  if (vertex_element == header.elements.end()) FailReading(name, "has no vertex element: it is not a point cloud");
  std::array<int, 3> xyz{-1, -1, -1};
  for (size_t i = 0; i < vertex_element->properties.size(); ++i) {
    const Property& property = vertex_element->properties[i];
    for (int axis = 0; axis < 3; ++axis) {
      if (property.name != std::string(1, static_cast<char>('x' + axis))) continue;
      if (property.list_count)
        FailReading(name, "its vertex property '" + property.name + "' is a list, not a coordinate" + kPlyRewrite);
      xyz[static_cast<size_t>(axis)] = static_cast<int>(i);
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (xyz[static_cast<size_t>(axis)] < 0) {
      FailReading(name, std::string("its vertices have no '") + static_cast<char>('x' + axis) +
                            "' property; fvm reads clouds of x, y, z points");
    }
  }
  if (vertex_element->count == 0) FailReading(name, "holds no points; export the cloud again");
  if (vertex_element->count > kMaxPoints) FailReading(name, "holds more points than fvm can hold");

  std::vector<Eigen::Vector3d> vertices;
  std::optional<std::vector<std::int64_t>> grid;  // range_grid: the vertex at each grid point, -1 for none
  Body body(bytes, header, name);
  for (const Element& element : header.elements) {
    const bool is_vertex = &element == &*vertex_element;
    const bool is_grid = element.name == "range_grid";
    if (is_vertex) vertices.reserve(static_cast<size_t>(element.count));
    if (is_grid) grid.emplace().reserve(static_cast<size_t>(element.count));
    for (std::uint64_t row = 0; row < element.count; ++row) {
      body.StartRow(element, row);
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      std::int64_t grid_vertex = -1;
      for (size_t i = 0; i < element.properties.size(); ++i) {
        const Property& property = element.properties[i];
        if (property.list_count) {
          const std::uint64_t length = body.ListLength(*property.list_count);
          for (std::uint64_t k = 0; k < length; ++k) {
            const double item = body.Next(property.type);
            if (is_grid && k == 0) {
              if (!(item >= 0 && item < static_cast<double>(vertex_element->count))) {
                FailReading(name, "its range_grid row " + std::to_string(row + 1) + " names vertex " +
                                      FormatShortest(item) + ", which does not exist" + kPlyRewrite);
              }
              grid_vertex = static_cast<std::int64_t>(item);
            }
          }
        } else {
          const double value = body.Next(property.type);
          for (int axis = 0; axis < 3; ++axis) {
            if (is_vertex && xyz[static_cast<size_t>(axis)] == static_cast<int>(i)) p[axis] = value * mm_per_unit;
          }
        }
      }
      body.EndRow();
      if (is_vertex) vertices.push_back(p);
      if (is_grid) grid->push_back(grid_vertex);
    }
  }
  body.CheckEnd();

  PointCloud cloud;
  if (grid) {
    const Eigen::Vector3d missing = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    if (grid->empty()) FailReading(name, "its range_grid element is empty" + std::string(kPlyRewrite));
    if (grid->size() > kMaxPoints) FailReading(name, "holds more points than fvm can hold");
    for (const std::int64_t index : *grid) cloud.points.push_back(index < 0 ? missing : vertices[static_cast<size_t>(index)]);
  } else {
    cloud.points = std::move(vertices);
  }
  const std::uint64_t n = cloud.points.size();
  if (header.columns && header.rows && *header.rows > 1 && *header.columns <= n && *header.rows <= n &&
      *header.columns * *header.rows == n) {
    cloud.width = static_cast<int>(*header.columns);
    cloud.height = static_cast<int>(*header.rows);
  } else {
    cloud.width = static_cast<int>(n);
    cloud.height = 1;
  }
  cloud.source = "PLY";
  return cloud;
}

}  // namespace fvm::imaging
