#pragma once
// Laser-tracker readings of a machine-tool verification (CSV), the contract between the measurement (or
// `fvm simulate tracker`) and `fvm verify`.
//
// The file: '#' comment lines, then a header naming
//   id,x,y,z                   the point and its nominal (commanded) machine coordinates, mm
//   xt,yt,zt                   what the tracker read, Cartesian in the tracker's frame, mm
//   or range,azimuth,elevation the same in the tracker's spherical coordinates, mm and rad (stage/tracker.h:
//                              azimuth from +x towards +y, elevation from the xy plane towards +z)
//   or xm,ym,zm                a CMM's measurement of a machined test piece (fvm testpiece), Cartesian in the
//                              CMM frame, mm: to the kinematics a CMM-measured piece is a tracker whose pose is
//                              the piece's datum
// and optionally `approach` (text: the direction the fastest axis last moved in, e.g. +x) and `tool` (1, 2, ...:
// which of the tool offsets given to `fvm verify --tool` the point was measured with; 1 when absent) and
// `cxx,cxy,cxz,cyy,cyz,czz` (all six or none, mm^2): the covariance of the measured point in the tracker frame, as
// `fvm multilaterate --verify-readings` writes it; `fvm verify` then weighs each point by its own covariance
// instead of one tracker's noise model. Other columns are ignored. Ids are text (P0001); each appears once. Column names match without regard to case; the CSV dialect
// is core/csv.h's.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fvm::artefacts {

inline constexpr int kMaxTools = 16;

struct TrackerReading {
  std::string id;
  Eigen::Vector3d nominal = Eigen::Vector3d::Zero();   // commanded machine coordinates, mm
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // tracker frame, Cartesian, mm (spherical input converted)
  std::string approach;                                // "" when not given
  int tool = 0;                                        // 0-based index of the tool offset (the file says 1, 2, ...)
  std::optional<Eigen::Matrix3d> covariance;           // of `measured`, mm^2, when the file gives one
  int line = 0;                                        // line of the source file; 0 when not read from a file
};

struct TrackerReadings {
  std::string source;                 // where it came from, for messages
  std::vector<std::string> comments;  // the '#' lines, without the '#'
  bool spherical = false;             // the file gave range,azimuth,elevation
  bool cmm = false;                   // the file gave xm,ym,zm (and is written so)
  std::vector<TrackerReading> points;  // file order
};

// Throws InputError "FILE:LINE: point ID: problem; what to do" on a missing file, a header with both the
// Cartesian and the spherical column set, with neither or with half of one, an empty id, a non-numeric, empty,
// NaN or infinite value, a duplicated id, no rows at all, a negative range, |elevation| > pi/2, |azimuth| > 2 pi,
// a covariance that is not positive definite (or given in some of its six columns only), or a coordinate or range
// beyond 100 m (a machine tool is not that large: the file is in micrometres or
// metres-times-something). The CSV layer bounds the file size and row count before anything grows.
TrackerReadings ReadTrackerReadings(const std::filesystem::path& path);

// Refuses (InputError "NAME: point ID (row N): problem") what ReadTrackerReadings would refuse in readings made in
// memory (a script's arrays): an empty or blank-padded id, a coordinate not finite or beyond 100 m, an id given
// twice, a tool outside 1 .. kMaxTools, a covariance not positive definite or given for some points only.
void CheckTrackerReadings(const TrackerReadings& data, const std::string& name);

// Whether the readings carry their own covariances (all points do or none: the reader and the check see to it).
inline bool CarriesCovariances(const TrackerReadings& data) {
  return !data.points.empty() && data.points.front().covariance.has_value();
}

// Writes id,x,y,z,xt,yt,zt (or range,azimuth,elevation when `spherical`) [,approach][,tool][,cxx..czz], comments first,
// atomically. Numbers are written as the shortest text that reads back to the same double (at least 1 nm and
// 1e-10 rad; Cartesian values round-trip bit for bit, spherical ones to ~1e-13 relative through the conversion).
// Refuses (InputError naming the file and point, nothing written) what ReadTrackerReadings would refuse.
void WriteTrackerReadings(const std::filesystem::path& path, const TrackerReadings& data);

}  // namespace fvm::artefacts
