#include "artefacts/io/tracker_readings.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <vector>

#include "core/dense_decomposition.h"
#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "stage/tracker.h"

namespace fvm::artefacts {
namespace {

// No machine tool measured with a tracker spans 100 m (the largest published one is 5 m): beyond that the file
// is in micrometres, or damaged.
constexpr double kMaxCoordinateMm = 100'000.0;
constexpr double kPi = std::numbers::pi;

const char* const kCartesian[3] = {"xt", "yt", "zt"};
const char* const kSpherical[3] = {"range", "azimuth", "elevation"};
// A CMM-measured test piece (fvm testpiece): the piece's points in the CMM frame, Cartesian like a tracker's.
const char* const kCmm[3] = {"xm", "ym", "zm"};
// A point's covariance (mm^2), upper triangle: what a multilateration knows of each point it located.
const char* const kCovariance[6] = {"cxx", "cxy", "cxz", "cyy", "cyz", "czz"};
constexpr int kCovarianceRow[6] = {0, 0, 0, 1, 1, 2}, kCovarianceCol[6] = {0, 1, 2, 1, 2, 2};

struct Columns {
  int id = -1;
  int nominal[3] = {-1, -1, -1};
  int measured[3] = {-1, -1, -1};
  bool spherical = false;
  bool cmm = false;
  int approach = -1;
  int tool = -1;
  int covariance[6] = {-1, -1, -1, -1, -1, -1};
  bool with_covariance = false;
};

// Which of three columns the header names, as "xt, yt" for messages.
std::string Named(const CsvTable& table, const char* const names[3]) {
  std::string out;
  for (int i = 0; i < 3; ++i) {
    if (table.Optional(names[i]) < 0) continue;
    if (!out.empty()) out += ", ";
    out += names[i];
  }
  return out;
}

Columns FindColumns(const CsvTable& table) {
  Columns c;
  c.id = table.Require("id");
  for (int axis = 0; axis < 3; ++axis) c.nominal[axis] = table.Require(std::string(1, "xyz"[axis]));
  const std::string cmm = Named(table, kCmm);
  const std::string where = fmt::format("{}:{}", table.name(), table.header_line());
  if (!cmm.empty() && !Named(table, kCartesian).empty()) {
    throw InputError(fmt::format("{}: the header names both tracker ({}) and CMM ({}) coordinates; give one set",
                                 where, Named(table, kCartesian), cmm));
  }
  c.cmm = !cmm.empty();
  const std::string cartesian = c.cmm ? cmm : Named(table, kCartesian);
  const std::string spherical = Named(table, kSpherical);
  if (!cartesian.empty() && !spherical.empty()) {
    throw InputError(fmt::format("{}: the header names tracker coordinates both Cartesian ({}) and spherical ({}); "
                                 "give one set: xt,yt,zt (mm) or range,azimuth,elevation (mm, rad)",
                                 where, cartesian, spherical));
  }
  if (cartesian.empty() && spherical.empty()) {
    throw InputError(fmt::format("{}: the header names no tracker coordinates; add xt,yt,zt (Cartesian, mm) or "
                                 "range,azimuth,elevation (mm, rad) beside id,x,y,z",
                                 where));
  }
  c.spherical = !spherical.empty();
  const char* const* names = c.spherical ? kSpherical : c.cmm ? kCmm : kCartesian;
  for (int i = 0; i < 3; ++i) {
    c.measured[i] = table.Optional(names[i]);
    if (c.measured[i] < 0) {
      throw InputError(fmt::format("{}: the header names {} but not '{}'; the tracker coordinates need all three of "
                                   "{},{},{}",
                                   where, c.spherical ? spherical : cartesian, names[i], names[0], names[1],
                                   names[2]));
    }
  }
  c.approach = table.Optional("approach");
  c.tool = table.Optional("tool");
  std::vector<std::string> given, missing;
  for (int k = 0; k < 6; ++k) {
    c.covariance[k] = table.Optional(kCovariance[k]);
    (c.covariance[k] >= 0 ? given : missing).emplace_back(kCovariance[k]);
  }
  if (!given.empty() && !missing.empty()) {
    throw InputError(fmt::format("{}: the header names the covariance columns {} but not {}; a point's covariance needs "
                                 "all six of cxx,cxy,cxz,cyy,cyz,czz (mm^2), or none",
                                 where, fmt::join(given, ","), fmt::join(missing, ",")));
  }
  c.with_covariance = !given.empty();
  return c;
}

bool IsCovariance(const Eigen::Matrix3d& v) {
  return v.allFinite() && Decompose<Eigen::LLT<Eigen::Matrix3d>>(v, "a reading's covariance").info() == Eigen::Success;
}

std::string PointName(std::string_view id) { return "point " + std::string(id); }

void CheckCoordinate(const CsvTable& table, const CsvRow& row, int column, const std::string& point, double v) {
  if (std::abs(v) > kMaxCoordinateMm) {
    table.Fail(row, fmt::format("{}: {} = {} is beyond 100 m; coordinates are in mm (is the file in micrometres?)",
                                point, table.header()[static_cast<size_t>(column)], v));
  }
}

TrackerReading ReadRow(const CsvTable& table, const CsvRow& row, const Columns& c) {
  TrackerReading reading;
  reading.line = row.line;
  reading.id = std::string(TrimBlanks(table.Text(row, c.id)));
  if (reading.id.empty()) table.Fail(row, "the id is empty; every point needs a name, e.g. P0001");
  const std::string point = PointName(reading.id);
  for (int axis = 0; axis < 3; ++axis) {
    const double v = table.Double(row, c.nominal[axis], point);
    CheckCoordinate(table, row, c.nominal[axis], point, v);
    reading.nominal[axis] = v;
  }
  double m[3];
  for (int i = 0; i < 3; ++i) m[i] = table.Double(row, c.measured[i], point);
  if (!c.spherical) {
    for (int i = 0; i < 3; ++i) CheckCoordinate(table, row, c.measured[i], point, m[i]);
    reading.measured = Eigen::Vector3d(m[0], m[1], m[2]);
  } else {
    if (m[0] < 0.0) {
      table.Fail(row, fmt::format("{}: range = {} is negative; a tracker's range is its distance to the reflector (mm)",
                                  point, m[0]));
    }
    CheckCoordinate(table, row, c.measured[0], point, m[0]);
    if (std::abs(m[1]) > 2.0 * kPi) {
      table.Fail(row, fmt::format("{}: azimuth = {} is beyond 2 pi; angles are in radians (degrees?)", point, m[1]));
    }
    if (std::abs(m[2]) > 0.5 * kPi) {
      table.Fail(row, fmt::format("{}: elevation = {} is beyond pi/2; angles are in radians, elevation from the "
                                  "tracker's xy plane (degrees? a zenith angle?)",
                                  point, m[2]));
    }
    reading.measured = stage::FromSpherical({m[0], m[1], m[2]});
  }
  if (c.approach >= 0) reading.approach = std::string(TrimBlanks(table.Text(row, c.approach)));
  if (c.tool >= 0) reading.tool = static_cast<int>(table.Int(row, c.tool, 1, kMaxTools, point)) - 1;
  if (c.with_covariance) {
    Eigen::Matrix3d v;
    for (int k = 0; k < 6; ++k) {
      v(kCovarianceRow[k], kCovarianceCol[k]) = v(kCovarianceCol[k], kCovarianceRow[k]) = table.Double(row, c.covariance[k], point);
    }
    if (!IsCovariance(v)) {
      table.Fail(row, fmt::format("{}: the covariance cxx..czz is not positive definite; variances are positive (mm^2) "
                                  "and each correlation below 1",
                                  point));
    }
    reading.covariance = v;
  }
  return reading;
}

}  // namespace

TrackerReadings ReadTrackerReadings(const std::filesystem::path& path) {
  CsvOptions options;
  options.expected_header = "id,x,y,z,xt,yt,zt";
  const CsvTable table = ReadCsv(path, options);
  const Columns columns = FindColumns(table);
  if (table.rows().empty()) {
    throw InputError(fmt::format("{}:{}: no point rows after the header; write one row per measured point",
                                 table.name(), table.header_line()));
  }
  TrackerReadings data;
  data.source = table.name();
  data.comments = table.comments();
  data.spherical = columns.spherical;
  data.cmm = columns.cmm;
  data.points.reserve(table.rows().size());
  std::map<std::string, int, std::less<>> first_line_of_id;
  for (const CsvRow& row : table.rows()) {
    TrackerReading reading = ReadRow(table, row, columns);
    const auto [it, inserted] = first_line_of_id.emplace(reading.id, row.line);
    if (!inserted) {
      table.Fail(row, fmt::format("{} appears again (first at line {}); each point is read once: rename or remove "
                                  "one of them",
                                  PointName(reading.id), it->second));
    }
    data.points.push_back(std::move(reading));
  }
  return data;
}

void CheckTrackerReadings(const TrackerReadings& data, const std::string& name) {
  std::map<std::string, size_t, std::less<>> seen;
  for (size_t i = 0; i < data.points.size(); ++i) {
    const TrackerReading& p = data.points[i];
    const auto refuse = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: point {} (row {}): {}", name, p.id.empty() ? "<no id>" : p.id, i + 1, problem));
    };
    if (TrimBlanks(p.id).empty()) refuse("the id is empty");
    if (TrimBlanks(p.id).size() != p.id.size()) refuse("the id has blanks at its ends, which a reader trims");
    if (!p.nominal.allFinite() || !p.measured.allFinite()) refuse("a coordinate is not finite");
    if (p.nominal.cwiseAbs().maxCoeff() > kMaxCoordinateMm || p.measured.cwiseAbs().maxCoeff() > kMaxCoordinateMm ||
        (data.spherical && p.measured.norm() > kMaxCoordinateMm)) {
      refuse("a coordinate is beyond 100 m");
    }
    if (!seen.emplace(p.id, i).second) refuse("the id appears twice");
    if (p.tool < 0 || p.tool >= kMaxTools) refuse(fmt::format("tool {} is not 1 .. {}", p.tool + 1, kMaxTools));
    if (p.covariance && !IsCovariance(*p.covariance)) refuse("the covariance is not positive definite");
    if (p.covariance.has_value() != CarriesCovariances(data)) {
      refuse("a covariance is given for some points only; give one for every point or for none");
    }
  }
}

void WriteTrackerReadings(const std::filesystem::path& path, const TrackerReadings& data) {
  try {
    CheckTrackerReadings(data, path.string());
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + "; nothing was written");
  }
  bool with_approach = false;
  bool with_tool = false;
  for (const TrackerReading& p : data.points) {
    with_approach = with_approach || !p.approach.empty();
    with_tool = with_tool || p.tool != 0;
  }
  if (data.points.empty()) {
    throw InputError(fmt::format("{}: no points to write; nothing was written", path.string()));
  }

  std::string out = CsvComments(data.comments);
  std::vector<std::string> header = {"id", "x", "y", "z"};
  for (const char* name : data.spherical ? kSpherical : data.cmm ? kCmm : kCartesian) header.emplace_back(name);
  if (with_approach) header.emplace_back("approach");
  if (with_tool) header.emplace_back("tool");
  const bool with_covariance = CarriesCovariances(data);  // all or none (checked above)
  if (with_covariance) header.insert(header.end(), std::begin(kCovariance), std::end(kCovariance));
  out += CsvLine(header);
  for (const TrackerReading& p : data.points) {
    std::vector<std::string> fields = {p.id, FormatShortest(p.nominal.x()), FormatShortest(p.nominal.y()),
                                       FormatShortest(p.nominal.z())};
    if (data.spherical) {
      const stage::Spherical s = stage::ToSpherical(p.measured);
      for (double v : {s.range_mm, s.azimuth_rad, s.elevation_rad}) fields.push_back(FormatShortest(v));
    } else {
      for (int i = 0; i < 3; ++i) fields.push_back(FormatShortest(p.measured[i]));
    }
    if (with_approach) fields.push_back(p.approach);
    if (with_tool) fields.push_back(std::to_string(p.tool + 1));
    for (int k = 0; with_covariance && k < 6; ++k) fields.push_back(FormatShortest((*p.covariance)(kCovarianceRow[k], kCovarianceCol[k])));
    out += CsvLine(fields);
  }
  WriteFileAtomically(path, out);
}

}  // namespace fvm::artefacts
