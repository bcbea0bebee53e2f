#pragma once
// The published row of the stitching-strategy study: calottes 1 and 6 of the grid, 20 mm apart along x
// ([Pérez 2019] Table 1, case a), in mm.

#include <Eigen/Core>

namespace fvm::testing {

inline const Eigen::Vector3d kPublishedRowFirst(-154.5487, -115.4767, -50.3624);
inline const Eigen::Vector3d kPublishedRowLast(-134.5409, -115.4371, -50.4457);

}  // namespace fvm::testing
