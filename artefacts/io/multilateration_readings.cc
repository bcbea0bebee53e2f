#include "artefacts/io/multilateration_readings.h"

#include <fmt/core.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <utility>

#include "core/csv.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "core/json_text.h"
#include "core/number_text.h"

namespace fvm::artefacts {
namespace {

// As for single-tracker readings: beyond 100 m the file is in micrometres, or damaged.
constexpr double kMaxMm = 100'000.0;
// A stations file is a few lines; anything beyond 16 MB is not one.
constexpr std::size_t kMaxStationsBytes = std::size_t{16} << 20;

std::string Context(std::string_view id, std::string_view station) {
  return fmt::format("point {}, station {}", id, station);
}

}  // namespace

MultilaterationReadings ReadMultilaterationReadings(const std::filesystem::path& path) {
  CsvOptions options;
  options.expected_header = "id,station,range";
  const CsvTable table = ReadCsv(path, options);
  const int c_id = table.Require("id");
  const int c_station = table.Require("station");
  const int c_range = table.Require("range");
  const int c_az = table.Optional("azimuth"), c_el = table.Optional("elevation");
  const int c_xyz[3] = {table.Optional("x"), table.Optional("y"), table.Optional("z")};
  const std::string header_at = fmt::format("{}:{}", table.name(), table.header_line());
  if ((c_az < 0) != (c_el < 0)) {
    throw InputError(fmt::format("{}: the header names {} but not {}; the angles need both azimuth and elevation (rad)",
                                 header_at, c_az >= 0 ? "azimuth" : "elevation", c_az >= 0 ? "elevation" : "azimuth"));
  }
  const int nominal_columns = (c_xyz[0] >= 0) + (c_xyz[1] >= 0) + (c_xyz[2] >= 0);
  if (nominal_columns != 0 && nominal_columns != 3) {
    throw InputError(fmt::format("{}: the header names {} of the nominal columns x,y,z; give all three (mm) or none",
                                 header_at, nominal_columns));
  }
  if (table.rows().empty()) {
    throw InputError(fmt::format("{}: no reading rows after the header; write one row per point and station", header_at));
  }
  MultilaterationReadings data;
  data.source = table.name();
  data.comments = table.comments();
  data.angles = c_az >= 0;
  data.nominal = nominal_columns == 3;
  data.rows.reserve(table.rows().size());
  std::map<std::pair<std::string, std::string>, int> first_line;
  std::map<std::string, std::pair<Eigen::Vector3d, int>, std::less<>> nominal_of;
  for (const CsvRow& row : table.rows()) {
    StationReadingRow r;
    r.line = row.line;
    r.id = std::string(TrimBlanks(table.Text(row, c_id)));
    r.station = std::string(TrimBlanks(table.Text(row, c_station)));
    if (r.id.empty()) table.Fail(row, "the id is empty; every point needs a name, e.g. P0001");
    if (r.station.empty()) table.Fail(row, fmt::format("point {}: the station is empty; name the station that read it", r.id));
    const std::string context = Context(r.id, r.station);
    r.range_mm = table.Double(row, c_range, context);
    if (!(r.range_mm > 0.0) || r.range_mm > kMaxMm) {
      table.Fail(row, fmt::format("{}: range = {} mm is {}", context, r.range_mm,
                                  r.range_mm > kMaxMm ? "beyond 100 m (is the file in micrometres?)"
                                                      : "not positive; a range is the distance to the reflector"));
    }
    if (data.angles) {
      r.azimuth_rad = table.Double(row, c_az, context);
      r.elevation_rad = table.Double(row, c_el, context);
      if (std::abs(r.azimuth_rad) > 2.0 * std::numbers::pi) {
        table.Fail(row, fmt::format("{}: azimuth = {} is beyond 2 pi; angles are in radians (degrees?)", context, r.azimuth_rad));
      }
      if (std::abs(r.elevation_rad) > 0.5 * std::numbers::pi) {
        table.Fail(row, fmt::format("{}: elevation = {} is beyond pi/2; angles are in radians, elevation from the "
                                    "station's xy plane (degrees? a zenith angle?)",
                                    context, r.elevation_rad));
      }
    }
    if (data.nominal) {
      for (int k = 0; k < 3; ++k) {
        r.nominal[k] = table.Double(row, c_xyz[k], context);
        if (std::abs(r.nominal[k]) > kMaxMm) {
          table.Fail(row, fmt::format("{}: {} = {} is beyond 100 m; coordinates are in mm", context, "xyz"[k], r.nominal[k]));
        }
      }
      const auto [it, inserted] = nominal_of.emplace(r.id, std::make_pair(r.nominal, row.line));
      if (!inserted && it->second.first != r.nominal) {
        table.Fail(row, fmt::format("point {}: nominal x,y,z differ from its row at line {}; a point has one nominal "
                                    "position",
                                    r.id, it->second.second));
      }
    }
    const auto [it, inserted] = first_line.emplace(std::make_pair(r.id, r.station), row.line);
    if (!inserted) {
      table.Fail(row, fmt::format("{}: read again (first at line {}); keep one reading per point and station",
                                  context, it->second));
    }
    data.rows.push_back(std::move(r));
  }
  return data;
}

void WriteMultilaterationReadings(const std::filesystem::path& path, const MultilaterationReadings& data) {
  if (data.rows.empty()) throw InputError(fmt::format("{}: no readings to write; nothing was written", path.string()));
  std::set<std::pair<std::string, std::string>> seen;
  for (size_t i = 0; i < data.rows.size(); ++i) {
    const StationReadingRow& r = data.rows[i];
    const auto refuse = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: row {} (point {}, station {}): {}; nothing was written", path.string(), i + 1,
                                   r.id, r.station, problem));
    };
    if (TrimBlanks(r.id).empty() || TrimBlanks(r.id).size() != r.id.size()) refuse("the id is empty or has blanks at its ends");
    if (TrimBlanks(r.station).empty() || TrimBlanks(r.station).size() != r.station.size()) {
      refuse("the station is empty or has blanks at its ends");
    }
    if (!(r.range_mm > 0.0) || r.range_mm > kMaxMm) refuse("the range is not in (0, 100 m]");
    if (data.angles && (!std::isfinite(r.azimuth_rad) || std::abs(r.azimuth_rad) > 2 * std::numbers::pi ||
                        !std::isfinite(r.elevation_rad) || std::abs(r.elevation_rad) > 0.5 * std::numbers::pi)) {
      refuse("an angle is out of range");
    }
    if (data.nominal && (!r.nominal.allFinite() || r.nominal.cwiseAbs().maxCoeff() > kMaxMm)) refuse("a nominal coordinate is out of range");
    if (!seen.emplace(r.id, r.station).second) refuse("the point is read twice by the station");
  }
  std::string out = CsvComments(data.comments);
  std::vector<std::string> header = {"id", "station", "range"};
  if (data.angles) header.insert(header.end(), {"azimuth", "elevation"});
  if (data.nominal) header.insert(header.end(), {"x", "y", "z"});
  out += CsvLine(header);
  for (const StationReadingRow& r : data.rows) {
    std::vector<std::string> f = {r.id, r.station, FormatShortest(r.range_mm)};
    if (data.angles) f.insert(f.end(), {FormatShortest(r.azimuth_rad), FormatShortest(r.elevation_rad)});
    if (data.nominal) {
      for (int k = 0; k < 3; ++k) f.push_back(FormatShortest(r.nominal[k]));
    }
    out += CsvLine(f);
  }
  WriteFileAtomically(path, out);
}

std::vector<Station> ReadStations(const std::filesystem::path& path) {
  const std::string text = ReadFileBytes(path, kMaxStationsBytes);
  const std::string file = path.string();
  nlohmann::json doc = ParseJsonText(text, file, "write {\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": 0, \"z\": 0}, ...]} (mm)");
  if (!doc.is_object() || !doc.contains("stations") || !doc["stations"].is_array()) {
    throw InputError(fmt::format("{}: no \"stations\" array; write {{\"stations\": [{{\"name\": \"A\", \"x\": 0, \"y\": "
                                 "0, \"z\": 0}}, ...]}} (mm)",
                                 file));
  }
  const nlohmann::json& list = doc["stations"];
  if (list.empty()) throw InputError(fmt::format("{}: the \"stations\" array is empty; list every station", file));
  std::vector<Station> out;
  std::set<std::string, std::less<>> names;
  for (size_t i = 0; i < list.size(); ++i) {
    const nlohmann::json& s = list[i];
    const auto fail = [&](const std::string& what) {
      return InputError(fmt::format("{}: stations[{}]: {}", file, i, what));
    };
    if (!s.is_object()) throw fail("not an object {\"name\", \"x\", \"y\", \"z\"}");
    if (!s.contains("name") || !s["name"].is_string()) throw fail("no text \"name\"");
    Station st;
    st.name = s["name"].get<std::string>();
    if (TrimBlanks(st.name).empty() || TrimBlanks(st.name).size() != st.name.size()) {
      throw fail(fmt::format("name '{}' is empty or has blanks at its ends", st.name));
    }
    for (int k = 0; k < 3; ++k) {
      const char* key = k == 0 ? "x" : k == 1 ? "y" : "z";
      if (!s.contains(key) || !s[key].is_number()) throw fail(fmt::format("station {}: no number \"{}\" (mm)", st.name, key));
      const double v = s[key].get<double>();
      if (!std::isfinite(v) || std::abs(v) > kMaxMm) {
        throw fail(fmt::format("station {}: {} = {} is beyond 100 m; coordinates are in mm", st.name, key, v));
      }
      st.position[k] = v;
    }
    if (!names.insert(st.name).second) throw fail(fmt::format("station {} appears twice; names are unique", st.name));
    out.push_back(std::move(st));
  }
  return out;
}

std::string StationsJson(const std::vector<Station>& stations) {
  nlohmann::json doc;
  doc["stations"] = nlohmann::json::array();
  for (const Station& s : stations) {
    doc["stations"].push_back({{"name", s.name}, {"x", s.position.x()}, {"y", s.position.y()}, {"z", s.position.z()}});
  }
  return doc.dump(2) + "\n";
}

void WriteMultilateratedPoints(const std::filesystem::path& path, const std::vector<MultilateratedPoint>& points,
                               const std::vector<std::string>& comments) {
  std::string out = CsvComments(comments);
  out += CsvLine({"id", "x", "y", "z", "u_x", "u_y", "u_z"});
  for (const MultilateratedPoint& p : points) {
    std::vector<std::string> f = {p.id};
    for (int k = 0; k < 3; ++k) f.push_back(FormatShortest(p.position[k]));
    for (int k = 0; k < 3; ++k) f.push_back(FormatShortest(p.u[k]));
    out += CsvLine(f);
  }
  WriteFileAtomically(path, out);
}

}  // namespace fvm::artefacts
