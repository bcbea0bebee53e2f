#pragma once
// A list of nominal points id,x,y,z (ids as text, mm; other columns ignored): the points.csv of `fvm simulate
// tracker`, or any point list a machine's compensation table is made for.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace fvm::artefacts {

struct ListedPoint {
  std::string id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm
};

// Throws InputError naming the file and line: no id, an id twice, a coordinate beyond 100 m, no points.
std::vector<ListedPoint> ReadPointList(const std::string& path);

}  // namespace fvm::artefacts
