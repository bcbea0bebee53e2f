#pragma once
// Multilateration data (fvm multilaterate): the readings of several tracker stations (CSV), the stations (JSON)
// and the multilaterated points (CSV).
//
// Readings CSV: '#' comment lines, then a header naming
//   id,station,range            the point (text), the station that read it (a name of the stations file) and the
//                               range, mm; one row per point and station
//   azimuth,elevation           optional, both or neither: the station's angles, rad (stage/tracker.h)
//   x,y,z                       optional, all or none: the point's nominal (commanded) machine coordinates, mm,
//                               the same on every row of the point (for fvm verify)
// Other columns are ignored; names match without regard to case; the dialect is core/csv.h's.
//
// Stations JSON: {"stations": [{"name": "A", "x": 0, "y": 0, "z": 0}, ...]} (mm); other keys are ignored, so the
// JSON that fvm multilaterate prints can be given back.
//
// Points CSV (written): '#' comments, id,x,y,z,u_x,u_y,u_z (mm; u: standard uncertainties).

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace fvm::artefacts {

struct StationReadingRow {
  std::string id;
  std::string station;
  double range_mm = 0.0;
  double azimuth_rad = 0.0;    // when MultilaterationReadings::angles
  double elevation_rad = 0.0;
  Eigen::Vector3d nominal = Eigen::Vector3d::Zero();  // when MultilaterationReadings::nominal
  int line = 0;                                        // 0 when not read from a file
};

struct MultilaterationReadings {
  std::string source;
  std::vector<std::string> comments;
  bool angles = false;   // azimuth,elevation columns
  bool nominal = false;  // x,y,z columns
  std::vector<StationReadingRow> rows;
};

// Throws InputError "FILE:LINE: point ID, station S: problem; what to do" on a missing file or column, half of the
// angle or nominal columns, an empty id or station, a non-numeric, NaN or infinite value, a range <= 0 or beyond
// 100 m, |azimuth| > 2 pi, |elevation| > pi/2, a point read twice by one station, a point whose nominal differs
// between its rows, or no rows.
MultilaterationReadings ReadMultilaterationReadings(const std::filesystem::path& path);
// Writes what the reader reads (shortest round-trip numbers), atomically; refuses what it would refuse.
void WriteMultilaterationReadings(const std::filesystem::path& path, const MultilaterationReadings& data);

struct Station {
  std::string name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
};

// Throws InputError "FILE: stations[2]: problem" on a missing file, text that is not JSON, no "stations" array,
// an empty list, an entry without a text name or numeric x, y, z, a duplicate name, or a coordinate beyond 100 m.
std::vector<Station> ReadStations(const std::filesystem::path& path);
std::string StationsJson(const std::vector<Station>& stations);  // {"stations": [...]}, 2-space indented

struct MultilateratedPoint {
  std::string id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
};
void WriteMultilateratedPoints(const std::filesystem::path& path, const std::vector<MultilateratedPoint>& points,
                               const std::vector<std::string>& comments);

}  // namespace fvm::artefacts
