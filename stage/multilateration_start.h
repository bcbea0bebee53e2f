#pragma once
// Where a multilateration starts (stage/multilateration.h): the 3-2-1 frame of a self-calibration, stations from
// the angles, each point from its ranges in closed form, and each station's rotation from its Cartesian readings.
// All closed form: no iteration, so the solve starts near its minimum and on the right side of the stations.

#include <Eigen/Core>
#include <vector>

#include "stage/multilateration.h"

namespace fvm::stage {

// The rigid transform that takes stations into the 3-2-1 frame (station 1 at the origin, 2 on +x, 3 in the xy
// plane on the +y side): x_frame = R x + t. Throws std::invalid_argument when the first three are on one line.
void ThreeTwoOneFrame(const std::vector<Eigen::Vector3d>& stations, Eigen::Matrix3d* rotation, Eigen::Vector3d* translation);

// Starting station positions from the angles: station 1 at the origin, its frame the common one; every other
// station by a rigid fit of its Cartesian readings to station 1's of the same points (at least 3 shared points).
// Throws std::invalid_argument naming the station otherwise.
std::vector<Eigen::Vector3d> StartStationsFromAngles(const MultilaterationProblem& problem);

// A point from its ranges in closed form: linear least squares on the differences of squared ranges with four
// or more stations that span 3D; otherwise in the stations' plane plus the height above it. The ranges cannot
// tell that point from its mirror image across the plane: it is taken on the side (s2 - s1) x (s3 - s1) of the
// first three stations points to, i.e. where they appear counter-clockwise (in a self-calibration: +z of the
// 3-2-1 frame). Multilaterate settles the side from the angles instead when every reading has them. Starts the
// Gauss-Newton solves.
Eigen::Vector3d TrilaterateClosedForm(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges_mm);

// TrilaterateClosedForm, and with `mirror` (when not null) the mirror image across the stations' plane when the
// ranges cannot tell the two apart (three stations, or all in one plane), else the same point.
Eigen::Vector3d Trilaterate(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges_mm,
                            Eigen::Vector3d* mirror);

// The best rotation of each station taking its Cartesian readings (range, azimuth, elevation) onto the directions
// to `points` from `stations` (into `rotations` when not null), and what is left: the sum of squared misfits (mm^2)
// over all stations. Every reading must carry angles.
double StationRotationMisfit(const MultilaterationProblem& problem, const std::vector<Eigen::Vector3d>& stations,
                             const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Matrix3d>* rotations);

}  // namespace fvm::stage
