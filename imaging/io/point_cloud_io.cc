#include "imaging/io/point_cloud_io.h"

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

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "imaging/io/cloud_codec.h"
#include "imaging/io/pcd_file.h"
#include "imaging/io/ply_file.h"
#include "imaging/io/reader_support.h"

namespace fvm::imaging {
namespace {

// Fields of a line: split at commas or semicolons when there are any, else at blanks.
std::vector<std::string_view> Fields(std::string_view line) {
  if (line.find_first_of(",;") == std::string_view::npos) return SplitWords(line);
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
  const std::vector<std::string_view> words = SplitWords(comment);
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
  const std::string extension = AsciiLower(path.extension().string());
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
  std::optional<std::uint64_t> declared_count;
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
      // A first line holding only the point count (NIST ATS .ds files): kept to check the count against.
      if (fields.size() == 1) {
        const std::optional<std::int64_t> count = ParseInt(fields[0]);
        if (count && *count >= 0) {
          declared_count = static_cast<std::uint64_t>(*count);
          continue;
        }
      }
      if (!fields.empty() && !ParseDouble(fields[0])) {  // a header naming the columns
        for (int axis = 0; axis < 3; ++axis) {
          const std::string wanted(1, static_cast<char>('x' + axis));
          columns[axis] = -1;
          for (size_t i = 0; i < fields.size(); ++i) {
            const std::string field = AsciiLower(fields[i]);
            if (field == wanted || field.rfind(wanted + "_", 0) == 0 || field.rfind(wanted + " ", 0) == 0 ||
                field.rfind(wanted + "(", 0) == 0 || field.rfind(wanted + "[", 0) == 0) {
              columns[axis] = static_cast<int>(i);
              break;
            }
          }
          // A header that names its columns but not this one: the cloud has no such coordinate.
          if (columns[axis] < 0) {
            throw InputError(where + ": the header names no column '" + wanted + "' (it has " +
                             QuotedForMessage(line) + "); a cloud needs x, y and z: name them, or leave the header out");
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
  if (declared_count && *declared_count != points.size()) {
    throw InputError(name + ":1: the first line says " + std::to_string(*declared_count) + " points, the file holds " +
                     std::to_string(points.size()) + "; the file is cut short or the count is wrong");
  }
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

void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<PointField>& extra,
                     const std::string& comment) {
  if (cloud.width < 0 || cloud.height < 0 ||
      cloud.points.size() != static_cast<std::size_t>(cloud.width) * static_cast<std::size_t>(cloud.height)) {
    throw std::invalid_argument("WritePointCloud: points.size() is not width * height");
  }
  for (const PointField& field : extra) {
    if (field.values.size() != cloud.points.size()) {
      throw std::invalid_argument("WritePointCloud: field " + field.name + " has not one value per point");
    }
  }
  const PointCloudFormat format = PointCloudFormatOf(path);
  if (format == PointCloudFormat::kXyz) {
    std::string text = "# fvm point cloud: x y z in mm, nan marks a missing point\n";
    if (!comment.empty()) text += "# " + comment + "\n";
    if (cloud.IsOrganised()) {
      text += "# grid " + std::to_string(cloud.width) + " x " + std::to_string(cloud.height) + "\n";
    }
    if (!extra.empty()) {
      text += "x y z";
      for (const PointField& field : extra) (text += ' ') += field.name;
      text += "\n";
    }
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
      const Eigen::Vector3d& p = cloud.points[i];
      text += FormatShortest(p.x()) + " " + FormatShortest(p.y()) + " " + FormatShortest(p.z());
      for (const PointField& field : extra) (text += ' ') += FormatShortest(field.values[i]);
      text += "\n";
    }
    WriteFileAtomically(path, text);
    return;
  }
  CloudBlob blob;
  blob.width = static_cast<std::uint32_t>(cloud.width);
  blob.height = static_cast<std::uint32_t>(cloud.height);
  blob.is_dense = std::all_of(cloud.points.begin(), cloud.points.end(), [](const auto& p) { return p.allFinite(); });
  for (int axis = 0; axis < 3; ++axis) {
    blob.fields.push_back({std::string(1, static_cast<char>('x' + axis)),
                           static_cast<std::uint32_t>(axis * sizeof(double)), CloudFieldType::kFloat64, 1});
  }
  for (std::size_t k = 0; k < extra.size(); ++k) {
    blob.fields.push_back({extra[k].name, static_cast<std::uint32_t>((3 + k) * sizeof(double)), CloudFieldType::kFloat64, 1});
  }
  blob.point_step = static_cast<std::uint32_t>((3 + extra.size()) * sizeof(double));
  blob.row_step = blob.point_step * blob.width;
  blob.data.resize(cloud.points.size() * blob.point_step);
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    std::uint8_t* record = blob.data.data() + i * blob.point_step;
    std::memcpy(record, cloud.points[i].data(), 3 * sizeof(double));
    for (std::size_t k = 0; k < extra.size(); ++k) {
      std::memcpy(record + (3 + k) * sizeof(double), &extra[k].values[i], sizeof(double));
    }
  }
  const CloudCodec& codec = LoadCloudCodec("writing " + path.string());
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    std::string why;
    if (!codec.write(temporary, format == PointCloudFormat::kPcd ? CloudFileType::kPcd : CloudFileType::kPly, blob,
                     &why)) {
      throw InputError(path.string() + ": cannot write" + (why.empty() ? "" : " (" + why + ")") +
                       "; check that the directory exists, is writable and has free space");
    }
  });
}

}  // namespace fvm::imaging
