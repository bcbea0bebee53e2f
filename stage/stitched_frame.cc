#include "stage/stitched_frame.h"

#include <ceres/jet.h>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <stdexcept>

#include "core/dense_decomposition.h"

namespace fvm::stage {

const char* StitchedFrameName(StitchedFrame frame) { return frame == StitchedFrame::kRotated ? "rotated" : "translated"; }

StitchedFrame ParseStitchedFrame(std::string_view name) {
  if (name == "rotated") return StitchedFrame::kRotated;
  if (name == "translated") return StitchedFrame::kTranslated;
  throw std::invalid_argument("unknown stitched frame '" + std::string(name) + "': use rotated or translated");
}

namespace {

template <typename T>
Eigen::Matrix<T, 3, 3> Turn(const ParameterLayout& layout, const T* free, const Eigen::Vector3d& first_tile,
                            const Eigen::Vector3d* reference) {
  Eigen::Matrix<T, 3, 3> turn = CameraOrientation(layout, free, first_tile, /*inverse=*/true);
  if (reference != nullptr) turn = turn * CameraOrientation(layout, free, *reference);
  return turn;
}

}  // namespace

Eigen::Matrix3d FirstTileTurn(StitchedFrame frame, const ParameterLayout& layout, const double* free,
                              const Eigen::Vector3d& first_tile, const Eigen::Vector3d* reference,
                              std::vector<Eigen::Matrix3d>* jacobian) {
  const int n = layout.NumFree();
  if (jacobian) jacobian->assign(static_cast<size_t>(n), Eigen::Matrix3d::Zero());
  if (frame == StitchedFrame::kTranslated) return Eigen::Matrix3d::Identity();
  if (jacobian == nullptr) return Turn(layout, free, first_tile, reference);
  // Forward-mode derivatives through the chain's rotations, one dual part per free coefficient.
  using Jet = ceres::Jet<double, kMaxCoefficients>;
  std::vector<Jet> jets(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) jets[static_cast<size_t>(k)] = Jet(free[k], k);
  const Eigen::Matrix<Jet, 3, 3> turn = Turn(layout, jets.data(), first_tile, reference);
  Eigen::Matrix3d value;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      value(r, c) = turn(r, c).a;
      for (int k = 0; k < n; ++k) (*jacobian)[static_cast<size_t>(k)](r, c) = turn(r, c).v[k];
    }
  }
  return value;
}

std::vector<std::string> TurnCoefficients(const ParameterLayout& layout) {
  std::vector<std::string> out;
  for (size_t i = 0; i < layout.coefficients().size(); ++i) {
    const ParameterLayout::Coefficient& c = layout.coefficients()[i];
    if (GetErrorTerm(c.term).kind == ErrorKind::kRotation && c.power >= 1 && layout.SlotOf(i) >= 0) out.push_back(c.name);
  }
  return out;
}

FirstTileFrame MakeFirstTileFrame(StitchedFrame frame, const ParameterLayout& layout, const double* free,
                                  const Eigen::Vector3d& first_tile, const Eigen::Vector3d* reference) {
  FirstTileFrame f;
  f.first_tile = first_tile;
  f.origin = Forward(layout, free, first_tile);
  f.turn = FirstTileTurn(frame, layout, free, first_tile, reference);
  return f;
}

Eigen::Vector3d TurnDisplacement(const Eigen::Vector3d& rotation, const Eigen::Vector3d& arm) { return -rotation.cross(arm); }

TurnFit FitTurn(const std::vector<Eigen::Vector3d>& residuals, const std::vector<Eigen::Vector3d>& arms) {
  // -w x d = d x w = Skew(d) w: one 3 x 3 block per observation.
  const Eigen::Index n = static_cast<Eigen::Index>(residuals.size());
  Eigen::MatrixXd a(3 * n, 3);
  Eigen::VectorXd b(3 * n);
  for (Eigen::Index k = 0; k < n; ++k) {
    a.block<3, 3>(3 * k, 0) = Skew(arms[static_cast<size_t>(k)]);
    b.segment<3>(3 * k) = residuals[static_cast<size_t>(k)];
  }
  // Directions with less than a percent of the measurement's lever arm (a flat bar's turn about its own length,
  // seen only through its tilt) are left out rather than amplified.
  // The threshold must be set before the decomposition: the orthogonal factor Z is built for the rank found
  // then, and a threshold lowered afterwards makes the solve read Z coefficients that were never computed.
  const auto cod = DecomposeWithThreshold<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(
      a, 1e-2, "the turn of a placement about its first tile (lever arms)");
  TurnFit fit;
  fit.solve = cod.pseudoInverse();
  fit.rotation = fit.solve * b;
  return fit;
}

}  // namespace fvm::stage
