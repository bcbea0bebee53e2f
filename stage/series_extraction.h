#pragma once
// Geometric verification of an XFYZ machine from a test piece's series ([Lorente 2021], second method), with extraction
// formulas derived from our own first-order model instead of the published ones (which carry sign typos: docs/commands/testpiece.md,
// "Geometric verification").
//
// The model (stage/axis_chain.h to first order; X moves the part, Y sits on the frame, Z rides on Y, the tool point
// at t = (0, 0, L) from Z, squareness carried by Y (xWy) and Z (xWz, yWz)): the deviation d = p - (q + t) of the
// point cut at command q = (x, y, z) is
//   d_x = EXY(y) + EXZ(z) - EXX(x) + L EBZ(z) + (z + L) EBY(y) - (z + L) EBX(x) + y ECX(x) - y xWy - z xWz
//   d_y = EYY(y) + EYZ(z) - EYX(x) - L EAZ(z) - (z + L) EAY(y) - x ECX(x) + (z + L) EAX(x) - z yWz
//   d_z = EZY(y) + EZZ(z) - EZX(x) - y EAX(x) + x EBX(x)
// Along a series only its own axis' coordinate varies, so every term of the other axes is a constant there. The
// formulas take differences between parallel series to cancel the terms they share, and the zero-reference step
// ([Lorente 2021] 6.2.3) subtracts each result's value at the axis' origin (extrapolated from the two series points
// nearest it), which removes every constant at once. With series X1, X2 (one XY plane, apart in y), X3 (X1's XZ plane,
// apart in z); Y1, Y2 (one XY plane, apart in x), Y3 (another height); Z1 (and Z2, Z3 in parallel planes):
//   ECX = (d_x[X1] - d_x[X2]) / (y1 - y2)          EBX = -(d_x[X1] - d_x[X3]) / (z1 - z3)
//   EAX = (d_y[X1] - d_y[X3]) / (z1 - z3)          EXX = -d_x[X1] - (z1 + L) EBX + y1 ECX
//   EYX = -d_y[X1] - x ECX + (z1 + L) EAX          EZX = -d_z[X1] - y1 EAX + x EBX
//   EBY = (d_x[Y3] - d_x[Ya] - y (ECX(x3) - ECX(xa))) / (z3 - za)          EAY = -(d_y[Y3] - d_y[Ya]) / (z3 - za)   (Ya: mean of Y1, Y2)
//   EYY = d_y[Ya] + (za + L) EAY                   EZY = d_z[Ya] + y EAX(xa)
//   EXY - y xWy = d_x[Ya] - (za + L) EBY - y ECX(xa)                                   (xa: mean of Y1's, Y2's x)
//   EZZ = d_z[Z1]        EXZ + L EBZ - z xWz = d_x[Z1] + (z + L) EBX(x1)        EYZ - L EAZ - z yWz = d_y[Z1] - (z + L) EAX(x1)
// (EAX, EBX, ECX at the Y and Z series' x interpolated from the X series; Z1 lies in the plane y = 0, where EAY and
// EBY vanish). What no formula can give on these
// series: ECY and ECZ (zero columns for a tool on the spindle axis), EAZ and EBZ apart from the straightness of Z
// (one tool length), and a squareness apart from the linear part of a straightness.

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace fvm::stage {

// One measured point of a series in the machine frame: the command and the deviation p - (q + t), mm.
struct SeriesPoint {
  Eigen::Vector3d command = Eigen::Vector3d::Zero();
  Eigen::Vector3d deviation = Eigen::Vector3d::Zero();
};

// One extracted error along its axis: coordinate (mm) and value (mm or rad), zero-referenced.
struct ExtractedError {
  std::string error;        // ISO 230-1 name, or a combination ("EXZ+L*EBZ-z*EB0Z")
  std::vector<double> coordinate, value;
};

// Applies the formulas above to the series named X1..Z3 (any missing series leaves out what needs it). Points of
// two series are paired by their axis coordinate (within 1 um). `tool_length` is L (mm).
// `origin` is the axes' origin (where the error functions vanish), the zero reference.
std::vector<ExtractedError> ExtractGeometricErrors(const std::map<std::string, std::vector<SeriesPoint>>& series, double tool_length,
                                                   const Eigen::Vector3d& origin);

}  // namespace fvm::stage
