#pragma once
// The frame of a stitched measurement: one convention for the simulators, identification, validation, correction
// and diagnosis.
//
// The instrument places the first tile of a stitched measurement at its encoder reading a ([Pérez 2019] 1.2) and every
// later tile by registration against it. Registration finds translations only, so the mosaic keeps the orientation
// in which the camera saw the part in that first tile. A part point P therefore shows up at
//     s = a + T (P - F(a)),   T = C(a)^-1    (rotated: what the instrument does)
//     s = a +   (P - F(a))                   (translated: the turn left out, the convention before)
// with F the stage's forward model ([Pérez 2019] eq. 1) and C(a) the camera's orientation in the part frame at a, d F /
// d(tool offset): for YXFZ C = R_X^-1 R_Y^-1, so T = R_Y R_X evaluated at a. Its yaw is tens of microradians on a stage
// of the published error size: a micrometre over 20 mm.
//
// An identified model knows the part frame only as its reference measurements saw it: the calibration of an
// uncalibrated artefact carries the orientation of the first tile of its first identification placement, r. The
// model's turn of a measurement starting at a is therefore relative, T = C(a)^-1 C(r), which constant rotations of
// the model leave unchanged. A simulator's truth has no reference: T = C(a)^-1.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stage/parameter_layout.h"

namespace fvm::stage {

enum class StitchedFrame { kTranslated, kRotated };

const char* StitchedFrameName(StitchedFrame frame);     // "translated", "rotated"
StitchedFrame ParseStitchedFrame(std::string_view name);  // throws std::invalid_argument naming the choices

// C(q) (or C(q)^-1) under the layout's model with the given free coefficient values.
template <typename T>
Eigen::Matrix<T, 3, 3> CameraOrientation(const ParameterLayout& layout, const T* free, const Eigen::Vector3d& q,
                                         bool inverse = false) {
  std::vector<T> all(layout.coefficients().size());
  layout.Expand(free, all.data());
  const Eigen::Matrix<T, 3, 1> qt = q.cast<T>();
  T e[kNumErrorTerms];
  layout.TermValues(all.data(), qt, e);
  T motion[kMotionErrors];
  MotionErrors(layout.chain(), e, qt, motion);
  return ChainOrientation(layout.chain(), motion, inverse);
}

// The turn T of the stitched frame of a measurement whose first tile is at `first_tile`: identity for kTranslated,
// C(a)^-1 C(r) for kRotated (C(a)^-1 without a reference). With `jacobian`, dT / d(free coefficient k) for every k.
Eigen::Matrix3d FirstTileTurn(StitchedFrame frame, const ParameterLayout& layout, const double* free,
                              const Eigen::Vector3d& first_tile, const Eigen::Vector3d* reference,
                              std::vector<Eigen::Matrix3d>* jacobian = nullptr);

// The coefficients through which a model's relative turn varies over the stage: its free rotation coefficients of
// power one or more. Empty: the model cannot tell one first tile's turn from another's.
std::vector<std::string> TurnCoefficients(const ParameterLayout& layout);

// One measurement's stitched frame: s = first_tile + turn (P - origin).
struct FirstTileFrame {
  Eigen::Vector3d first_tile = Eigen::Vector3d::Zero();  // a, the first tile's encoder reading
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();      // F(a), where the stage really put it (part frame)
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  Eigen::Vector3d Stitched(const Eigen::Vector3d& part) const { return first_tile + turn * (part - origin); }
};
FirstTileFrame MakeFirstTileFrame(StitchedFrame frame, const ParameterLayout& layout, const double* free,
                                  const Eigen::Vector3d& first_tile, const Eigen::Vector3d* reference);

// The turn about its first tile that best explains one measurement's residuals (model - stitched), the rotation
// its stitched frame has that the model did not give it: r_i ~ -w x d_i with d_i = s_i - a, by least squares. A
// bar turned about its own length shows nothing: the minimum-norm solution leaves that part at zero.
struct TurnFit {
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // rad, small rotation vector
  Eigen::MatrixXd solve;                               // 3 x 3n: rotation = solve * stacked residuals
};
TurnFit FitTurn(const std::vector<Eigen::Vector3d>& residuals, const std::vector<Eigen::Vector3d>& arms);
// -w x d, the displacement a turn w about the first tile gives a point at arm d.
Eigen::Vector3d TurnDisplacement(const Eigen::Vector3d& rotation, const Eigen::Vector3d& arm);

}  // namespace fvm::stage
