#pragma once
// A list of nominal points id,x,y,z (ids as text, mm; an `approach` column kept, other columns ignored): the
// points.csv of `fvm simulate tracker`, the nominal points of a multilateration, or any point list a machine's
// compensation table is made for.

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace fvm::artefacts {

struct ListedPoint {
  std::string id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
  std::string approach;                                // the direction the machine came from ("" without the column)
};

// In the file's order. Throws InputError naming the file and line: no id, an id twice, a coordinate beyond 100 m,
// no points.
std::vector<ListedPoint> ReadPointList(const std::filesystem::path& path);

// The same points looked up by id (ids are unique: ReadPointList refuses a repeat).
std::map<std::string, ListedPoint, std::less<>> PointsById(std::vector<ListedPoint> points);

}  // namespace fvm::artefacts
