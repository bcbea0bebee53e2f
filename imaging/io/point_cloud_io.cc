#include "imaging/io/point_cloud_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/input_error.h"
#include "core/file_io.h"
#include "core/number_text.h"
#include "imaging/io/pcd_file.h"
#include "imaging/io/ply_file.h"

namespace fvm::imaging {
namespace {

constexpr std::uint64_t kMaxPoints = std::numeric_limits<int>::max();

[[noreturn]] void Fail(const std::string& name, const std::string& problem) { throw InputError(name + ": " + problem); }

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// PCL reports problems on the console in its own words; ours name the file and what to do instead.
class QuietPcl {
 public:
  QuietPcl() : previous_(pcl::console::getVerbosityLevel()) { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); }
  ~QuietPcl() { pcl::console::setVerbosityLevel(previous_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL previous_;
};

std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t start = 0;
  while (true) {
    start = line.find_first_not_of(" \t\r", start);
    if (start == std::string_view::npos) break;
    const size_t end = std::min(line.find_first_of(" \t\r", start), line.size());
    words.push_back(line.substr(start, end - start));
    start = end;
  }
  return words;
}

// PCL trusts the header: a damaged one can make it allocate terabytes or crash (empty FIELDS, say). So the
// header is checked here, as strictly as the format allows, before PCL sees the file.
struct HeaderLines {
  std::vector<std::vector<std::string_view>> lines;  // words of each line, comments and blank lines left out
  std::size_t data_offset = 0;                       // first byte after the header
};

// Lines up to and including the one whose first word is `last` (case-insensitive).
HeaderLines SplitHeader(const std::string& name, std::string_view head, const std::string& last,
                        const std::string& format) {
  HeaderLines header;
  size_t start = 0;
  while (start < head.size()) {
    const size_t newline = head.find('\n', start);
    if (newline == std::string_view::npos) break;
    const std::string_view line = head.substr(start, newline - start);
    start = newline + 1;
    const std::vector<std::string_view> words = Words(line);
    if (words.empty() || words[0].front() == '#') continue;
    header.lines.push_back(words);
    if (Lower(words[0]) == last) {
      header.data_offset = start;
      return header;
    }
  }
  Fail(name, "its " + format + " header does not end (no '" + last + "' line in the first " +
                 std::to_string(head.size()) + " bytes); the file is damaged or not " + format);
}

std::optional<std::uint64_t> Count(std::string_view word) {
  const std::optional<std::int64_t> value = ParseInt(word);
  if (!value || *value < 0) return std::nullopt;
  return static_cast<std::uint64_t>(*value);
}

void CheckPcdHeader(const std::string& name, std::string_view head, std::size_t file_size) {
  const std::string bad = "; the file is damaged: write it again";
  const HeaderLines header = SplitHeader(name, head, "data", "PCD");
  std::vector<std::string_view> fields, sizes, types, counts;
  std::optional<std::uint64_t> width, height, points;
  std::string data;
  for (const std::vector<std::string_view>& words : header.lines) {
    const std::string key = Lower(words[0]);
    const std::vector<std::string_view> values(words.begin() + 1, words.end());
    if (key == "version" || key == "viewpoint") continue;
    if (key == "fields")
      fields = values;
    else if (key == "size")
      sizes = values;
    else if (key == "type")
      types = values;
    else if (key == "count")
      counts = values;
    else if (key == "width" && values.size() == 1)
      width = Count(values[0]);
    else if (key == "height" && values.size() == 1)
      height = Count(values[0]);
    else if (key == "points" && values.size() == 1)
      points = Count(values[0]);
    else if (key == "data" && values.size() == 1)
      data = Lower(values[0]);
    else
      Fail(name, "unexpected PCD header line '" + key + "'" + bad);
  }
  if (counts.empty()) counts.assign(fields.size(), "1");
  if (fields.empty() || sizes.size() != fields.size() || types.size() != fields.size() ||
      counts.size() != fields.size()) {
    Fail(name, "its PCD header does not give SIZE, TYPE and COUNT for each of its FIELDS" + bad);
  }
  std::uint64_t point_step = 0;
  for (size_t i = 0; i < fields.size(); ++i) {
    const std::optional<std::uint64_t> size = Count(sizes[i]), count = Count(counts[i]);
    const std::string type = Lower(types[i]);
    const bool valid_type = (type == "i" || type == "u") ? (size == 1u || size == 2u || size == 4u || size == 8u)
                                                         : type == "f" && (size == 4u || size == 8u);
    if (!valid_type || !count || *count < 1 || *count > 1000000) {
      Fail(name, "its PCD field '" + std::string(fields[i]) + "' has no valid SIZE, TYPE and COUNT" + bad);
    }
    point_step += *size * *count;
  }
  if (!width || !height) Fail(name, "its PCD header has no valid WIDTH and HEIGHT" + bad);
  if (*width > kMaxPoints || *height > kMaxPoints || *width * *height > kMaxPoints ||
      (points && *points != *width * *height)) {
    Fail(name, "its PCD header's WIDTH x HEIGHT and POINTS disagree or are beyond what fvm can hold" + bad);
  }
  const std::uint64_t n = *width * *height;
  const std::uint64_t room = file_size - header.data_offset;
  std::uint64_t needed = 0;
  if (data == "ascii") {
    needed = n;  // each point takes at least a digit or a line
  } else if (data == "binary") {
    needed = n * point_step;
  } else if (data == "binary_compressed") {
    needed = n * point_step / 1000;  // LZF compresses no better than that
  } else {
    Fail(name, "its PCD DATA is '" + data + "', not ascii, binary or binary_compressed" + bad);
  }
  if (needed > room) {
    Fail(name, "the header declares " + std::to_string(n) + " points, more than the file's " +
                   std::to_string(file_size) + " bytes can hold; the file is damaged or incomplete: write it again");
  }
}

void CheckPlyHeader(const std::string& name, std::string_view head, std::size_t file_size) {
  const std::string bad = "; the file is damaged: write it again";
  const HeaderLines header = SplitHeader(name, head, "end_header", "PLY");
  if (header.lines.empty() || header.lines[0][0] != "ply") Fail(name, "does not start with 'ply'" + bad);
  std::uint64_t total = 0;
  bool vertex = false;
  for (const std::vector<std::string_view>& words : header.lines) {
    const std::string key = Lower(words[0]);
    if (key == "element") {
      const std::optional<std::uint64_t> count = words.size() == 3 ? Count(words[2]) : std::nullopt;
      if (!count || *count > kMaxPoints) Fail(name, "has a PLY element without a valid count" + bad);
      total += *count;
      vertex = vertex || words[1] == "vertex";
    } else if (key == "format") {
      if (words.size() != 3 ||
          (words[1] != "ascii" && words[1] != "binary_little_endian" && words[1] != "binary_big_endian")) {
        Fail(name, "has an unknown PLY format line" + bad);
      }
    } else if (key == "property") {
      const bool list = words.size() == 5 && words[1] == "list";
      if (words.size() != 3 && !list) Fail(name, "has a malformed PLY property line" + bad);
    } else if (key != "ply" && key != "comment" && key != "obj_info" && key != "end_header") {
      Fail(name, "unexpected PLY header line '" + key + "'" + bad);
    }
  }
  if (!vertex) Fail(name, "has no vertex element: not a point cloud");
  // Every element takes at least a byte of the file.
  if (total > file_size - header.data_offset) {
    Fail(name, "the header declares " + std::to_string(total) + " elements, more than the file's " +
                   std::to_string(file_size) + " bytes can hold; the file is damaged or incomplete: write it again");
  }
}

double ReadValue(const std::uint8_t* p, std::uint8_t datatype) {
  const auto load = [p](auto value) {
    std::memcpy(&value, p, sizeof value);
    return static_cast<double>(value);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8:
      return load(std::int8_t{});
    case pcl::PCLPointField::UINT8:
      return load(std::uint8_t{});
    case pcl::PCLPointField::INT16:
      return load(std::int16_t{});
    case pcl::PCLPointField::UINT16:
      return load(std::uint16_t{});
    case pcl::PCLPointField::INT32:
      return load(std::int32_t{});
    case pcl::PCLPointField::UINT32:
      return load(std::uint32_t{});
    case pcl::PCLPointField::FLOAT32:
      return load(float{});
    default:
      return load(double{});
  }
}

PointCloud ExtractXyz(const pcl::PCLPointCloud2& blob, const std::string& name, const PointCloudReadOptions& options) {
  const pcl::PCLPointField* fields[3] = {nullptr, nullptr, nullptr};
  for (const pcl::PCLPointField& field : blob.fields) {
    for (int axis = 0; axis < 3; ++axis) {
      if (field.name == std::string(1, static_cast<char>('x' + axis)) && fields[axis] == nullptr) fields[axis] = &field;
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    const pcl::PCLPointField* field = fields[axis];
    if (field == nullptr) {
      Fail(name,
           std::string("has no '") + static_cast<char>('x' + axis) + "' field; fvm reads clouds of x, y, z points");
    }
    const std::size_t size = pcl::getFieldSize(field->datatype);
    if (size == 0 || field->count < 1 || field->offset + size > blob.point_step) {
      Fail(name, "its '" + field->name + "' field does not fit the point record; the file is damaged: write it again");
    }
  }
  const std::uint64_t width = blob.width, height = blob.height;
  const std::uint64_t n = width * height;
  if (n == 0) Fail(name, "holds no points; export the cloud again");
  if (n > kMaxPoints || blob.row_step < width * blob.point_step ||
      blob.data.size() < (height - 1) * blob.row_step + width * blob.point_step) {
    Fail(name, "its header and data disagree on the number of points; the file is damaged: write it again");
  }
  PointCloud cloud;
  cloud.width = static_cast<int>(width);
  cloud.height = static_cast<int>(height);
  cloud.points.reserve(static_cast<std::size_t>(n));
  for (std::uint64_t row = 0; row < height; ++row) {
    for (std::uint64_t col = 0; col < width; ++col) {
      const std::uint8_t* point = blob.data.data() + row * blob.row_step + col * blob.point_step;
      Eigen::Vector3d p;
      for (int axis = 0; axis < 3; ++axis) {
        p[axis] = ReadValue(point + fields[axis]->offset, fields[axis]->datatype) * options.mm_per_unit;
      }
      cloud.points.push_back(p);
    }
  }
  return cloud;
}

[[maybe_unused]] PointCloud ReadWithPcl(const std::filesystem::path& path, PointCloudFormat format,
                       const PointCloudReadOptions& options) {
  const std::string name = path.string();
  const std::size_t size = CheckReadableFile(path);
  const bool pcd = format == PointCloudFormat::kPcd;
  const std::string head = ReadFileHead(path, 65536);
  if (pcd) {
    CheckPcdHeader(name, head, size);
  } else {
    CheckPlyHeader(name, head, size);
  }
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  int result = -1;
  std::string why;
  {
    const QuietPcl quiet;
    try {
      if (pcd) {
        pcl::PCDReader reader;
        result = reader.read(name, blob, origin, orientation, version, 0);
      } else {
        pcl::PLYReader reader;
        result = reader.read(name, blob, origin, orientation, version, 0);
      }
    } catch (const std::exception& e) {
      why = std::string(" (") + e.what() + ")";
      result = -1;
    }
  }
  if (result < 0) {
    Fail(name, std::string("PCL cannot read it as ") + (pcd ? "PCD" : "PLY") + why +
                   "; the file is damaged, or not a point cloud of this format");
  }
  PointCloud cloud = ExtractXyz(blob, name, options);
  cloud.source = pcd ? "PCD" : "PLY";
  return cloud;
}

// Fields of a line: split at commas or semicolons when there are any, else at blanks.
std::vector<std::string_view> Fields(std::string_view line) {
  if (line.find_first_of(",;") == std::string_view::npos) return Words(line);
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t end = std::min(line.find_first_of(",;", start), line.size());
    fields.push_back(TrimBlanks(line.substr(start, end - start)));
    if (end == line.size()) break;
    start = end + 1;
  }
  if (!fields.empty() && fields.back().empty()) fields.pop_back();  // a trailing separator
  return fields;
}

std::optional<std::pair<int, int>> GridComment(std::string_view comment) {
  const std::vector<std::string_view> words = Words(comment);
  if (words.size() != 4 || words[0] != "grid" || words[2] != "x") return std::nullopt;
  const std::optional<std::int64_t> w = ParseInt(words[1]), h = ParseInt(words[3]);
  if (!w || !h || *w < 1 || *h < 1 || *w > INT32_MAX || *h > INT32_MAX) return std::nullopt;
  return std::make_pair(static_cast<int>(*w), static_cast<int>(*h));
}

}  // namespace

void PointCloudReadOptions::Check() const {
  if (!(mm_per_unit > 0.0) || !std::isfinite(mm_per_unit)) {
    throw InputError("point-cloud options: mm per unit must be positive, e.g. 1000 for clouds in metres");
  }
}

PointCloudFormat PointCloudFormatOf(const std::filesystem::path& path) {
  const std::string extension = Lower(path.extension().string());
  if (extension == ".pcd") return PointCloudFormat::kPcd;
  if (extension == ".ply") return PointCloudFormat::kPly;
  return PointCloudFormat::kXyz;
}

PointCloud ParseXyz(std::string_view text, const std::string& name, const PointCloudReadOptions& options) {
  options.Check();
  std::vector<Eigen::Vector3d> points;
  std::optional<std::pair<int, int>> grid;
  int columns[3] = {0, 1, 2};
  bool seen_data_or_header = false;
  std::size_t line_number = 0;
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view line = TrimBlanks(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    const std::string where = name + ":" + std::to_string(line_number);
    if (line.empty()) continue;
    if (line.front() == '#') {
      if (!grid) grid = GridComment(line.substr(1));
      continue;
    }
    const std::vector<std::string_view> fields = Fields(line);
    if (!seen_data_or_header) {
      seen_data_or_header = true;
      if (!fields.empty() && !ParseDouble(fields[0])) {  // a header naming the columns
        for (int axis = 0; axis < 3; ++axis) {
          const std::string wanted(1, static_cast<char>('x' + axis));
          for (size_t i = 0; i < fields.size(); ++i) {
            const std::string field = Lower(fields[i]);
            if (field == wanted || field.rfind(wanted + "_", 0) == 0 || field.rfind(wanted + " ", 0) == 0 ||
                field.rfind(wanted + "(", 0) == 0) {
              columns[axis] = static_cast<int>(i);
              break;
            }
          }
        }
        continue;
      }
    }
    const int needed = std::max({columns[0], columns[1], columns[2]}) + 1;
    if (static_cast<int>(fields.size()) < needed) {
      throw InputError(where + ": " + std::to_string(fields.size()) + " fields where x, y, z need " +
                       std::to_string(needed) + "; XYZ files hold x y z (mm) per line");
    }
    Eigen::Vector3d p;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view field = fields[static_cast<size_t>(columns[axis])];
      const std::optional<double> value = ParseDouble(field);
      if (!value) {
        throw InputError(where + ": '" + std::string(field.substr(0, 40)) +
                         "' is not a number; XYZ files hold "
                         "x y z (mm) per line, '#' starts a comment");
      }
      p[axis] = *value * options.mm_per_unit;
    }
    points.push_back(p);
    if (points.size() > kMaxPoints) throw InputError(name + ": more points than fvm can hold");
  }
  if (points.empty()) throw InputError(name + ": holds no points; XYZ files hold x y z (mm) per line");
  PointCloud cloud = MakeUnorganisedCloud(std::move(points));
  if (grid &&
      static_cast<std::uint64_t>(grid->first) * static_cast<std::uint64_t>(grid->second) == cloud.points.size()) {
    cloud.width = grid->first;
    cloud.height = grid->second;
  }
  cloud.source = "XYZ text";
  return cloud;
}

PointCloud ReadPointCloud(const std::filesystem::path& path, PointCloudFormat format,
                          const PointCloudReadOptions& options) {
  options.Check();
  if (format == PointCloudFormat::kXyz) {
    CheckReadableFile(path);
    return ParseXyz(ReadFileBytes(path), path.string(), options);
  }
  CheckReadableFile(path);
  const std::string bytes = ReadFileBytes(path);
  return format == PointCloudFormat::kPcd ? ParsePcd(bytes, path.string(), options.mm_per_unit)
                                          : ParsePly(bytes, path.string(), options.mm_per_unit);
}

PointCloud ReadPointCloud(const std::filesystem::path& path, const PointCloudReadOptions& options) {
  return ReadPointCloud(path, PointCloudFormatOf(path), options);
}

void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud) {
  if (cloud.width < 0 || cloud.height < 0 ||
      cloud.points.size() != static_cast<std::size_t>(cloud.width) * static_cast<std::size_t>(cloud.height)) {
    throw std::invalid_argument("WritePointCloud: points.size() is not width * height");
  }
  const PointCloudFormat format = PointCloudFormatOf(path);
  if (format == PointCloudFormat::kXyz) {
    std::string text = "# fvm point cloud: x y z in mm, nan marks a missing point\n";
    if (cloud.IsOrganised()) {
      text += "# grid " + std::to_string(cloud.width) + " x " + std::to_string(cloud.height) + "\n";
    }
    for (const Eigen::Vector3d& p : cloud.points) {
      text += FormatShortest(p.x()) + " " + FormatShortest(p.y()) + " " + FormatShortest(p.z()) + "\n";
    }
    WriteFileAtomically(path, text);
    return;
  }
  pcl::PCLPointCloud2 blob;
  blob.width = static_cast<std::uint32_t>(cloud.width);
  blob.height = static_cast<std::uint32_t>(cloud.height);
  blob.is_dense = std::all_of(cloud.points.begin(), cloud.points.end(), [](const auto& p) { return p.allFinite(); });
  for (int axis = 0; axis < 3; ++axis) {
    pcl::PCLPointField field;
    field.name = std::string(1, static_cast<char>('x' + axis));
    field.offset = static_cast<std::uint32_t>(axis * sizeof(double));
    field.datatype = pcl::PCLPointField::FLOAT64;
    field.count = 1;
    blob.fields.push_back(field);
  }
  blob.point_step = 3 * sizeof(double);
  blob.row_step = blob.point_step * blob.width;
  blob.data.resize(cloud.points.size() * blob.point_step);
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    std::memcpy(blob.data.data() + i * blob.point_step, cloud.points[i].data(), blob.point_step);
  }
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    const QuietPcl quiet;
    int result = -1;
    if (format == PointCloudFormat::kPcd) {
      result = pcl::PCDWriter().writeBinary(temporary.string(), blob);
    } else {
      result = pcl::PLYWriter().writeBinary(temporary.string(), blob, Eigen::Vector4f::Zero(),
                                            Eigen::Quaternionf::Identity(), false);
    }
    if (result < 0) {
      throw InputError(path.string() +
                       ": cannot write; check that the directory exists, is writable and has "
                       "free space");
    }
  });
}

}  // namespace fvm::imaging
