#pragma once
// Kinematic chains of three linear axes in F notation, and the forward model that maps axis commands and
// error-term values to the coordinates of the tool point in the part frame.
//
// Convention (one for every chain, derived from the sources; tests/stage/*chain* and published_model_test check it):
// - "YXFZ": F is the fixed frame; letters left of F move the part, letters right of F move the tool. On each
//   side the letters read left to right go from the frame outward: in YXFZ the Y carriage sits on the frame and
//   X rides on Y ([Pérez thesis] 2.7); in XFYZ, Y sits on the frame and Z rides on Y ([Aguado 2016] eq. 1).
// - Each axis k commanded to q_k is a rigid motion A_k(v) = T_k + R_k v. Tool-side axes translate by +q_k,
//   part-side axes by -q_k (moving the table +x moves the part -x under the tool):
//       T_k = +-q_k e_k + (kTx, kTy, kTz)(q_k) - q_k * W(q_k) e_other   (for each squareness term k carries)
//       R_k = I + [eps_k]x with eps_k = (kRx, kRy, kRz)(q_k)   (eq. 2; or the exact rotation of eps_k)
// - Tool point in the frame: w = A_t1(A_t2(... A_tn(tool_offset))); part coordinates of it:
//       p = A_pn^-1(... A_p1^-1(w)),  A^-1(v) = R^-1 (v - T)
//   For YXFZ with no Z errors this is the published eq. 1: TP = RX^-1 [RY^-1 (TL - TY) - TX] ([Pérez 2019]).
// - An optional instrument frame carried by the part (a laser tracker on the table) maps p into its own
//   coordinates: X_LT = R_LT^-1 (p - T_LT) ([Aguado 2016]).
// - A squareness term xWy tilts the motion of one of its two axes, its carrier: kPartEnd picks the axis nearer
//   the part along part -> frame -> tool (the published FVM model: X carries xWy and xWz, Y carries yWz);
//   kToolEnd picks the one nearer the tool (the machine-tool seeds: in XFYZ, Y carries xWy, Z the others).
// With no errors the forward model is the identity: p = q.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stage/error_terms.h"
#include "stage/pose.h"

namespace fvm::stage {

enum class RotationModel {
  kSmallAngle,  // R = I + [eps]x exactly as the sources write it; its inverse is the true matrix inverse
  kExact,       // R = exp([eps]x), a proper rotation
};

enum class SquarenessCarrier { kPartEnd, kToolEnd };

struct AxisChain {
  std::string code;              // "YXFZ"
  std::vector<Axis> part_axes;   // frame outward: part_axes[0] is mounted on the frame
  std::vector<Axis> tool_axes;   // frame outward
  std::array<Axis, 3> squareness_carrier{Axis::kX, Axis::kX, Axis::kY};  // for xWy, xWz, yWz
  Eigen::Vector3d tool_offset = Eigen::Vector3d::Zero();                // mm, in the last tool axis' frame
  std::optional<Pose> instrument;  // measuring-instrument frame carried by the part
  RotationModel rotation_model = RotationModel::kSmallAngle;

  // Throws std::invalid_argument naming what is wrong ("YXFZ" needs each of X, Y, Z once and one F).
  static AxisChain Parse(std::string_view code, SquarenessCarrier carrier = SquarenessCarrier::kToolEnd);
  // The published focus-variation microscope stage: YXFZ, X carries xWy and xWz, Y carries yWz.
  static AxisChain FvmStage();

  // The axis whose coordinate a term's polynomial takes: its own axis (T, R) or its carrier (W).
  Axis ArgumentAxis(int term) const;
  bool IsPartSide(Axis axis) const;
};

namespace internal {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

template <typename T>
Vec3<T> Cross(const Vec3<T>& a, const Vec3<T>& b) {
  return Vec3<T>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

// Nominal motion of an axis plus its translation error (error terms and the squareness it carries).
template <typename T>
Vec3<T> AxisTranslation(const AxisChain& chain, Axis axis, const T* motion, const Vec3<T>& q) {
  const int k = static_cast<int>(axis);
  Vec3<T> t(motion[6 * k], motion[6 * k + 1], motion[6 * k + 2]);
  t[k] += chain.IsPartSide(axis) ? T(-q[k]) : T(q[k]);
  return t;
}

template <typename T>
Vec3<T> AxisRotation(Axis axis, const T* motion) {
  const int k = static_cast<int>(axis);
  return Vec3<T>(motion[6 * k + 3], motion[6 * k + 4], motion[6 * k + 5]);
}

template <typename T>
Vec3<T> Rotate(RotationModel model, const Vec3<T>& eps, const Vec3<T>& v) {
  if (model == RotationModel::kSmallAngle) return v + Cross(eps, v);
  Vec3<T> out;
  ceres::AngleAxisRotatePoint(eps.data(), v.data(), out.data());
  return out;
}

template <typename T>
Vec3<T> RotateInverse(RotationModel model, const Vec3<T>& eps, const Vec3<T>& v) {
  if (model == RotationModel::kSmallAngle) {
    // (I + [e]x)^-1 = (I - [e]x + e e^T) / (1 + |e|^2): exact, no matrix inverse needed.
    return (v - Cross(eps, v) + eps * eps.dot(v)) / (T(1.0) + eps.squaredNorm());
  }
  const Vec3<T> minus = -eps;
  Vec3<T> out;
  ceres::AngleAxisRotatePoint(minus.data(), v.data(), out.data());
  return out;
}

}  // namespace internal

// The motion errors of the three axes, 6 per axis: translation error (kTx, kTy, kTz and, for a squareness
// term the axis carries, -q_k * W in the other axis' direction) and rotation vector (kRx, kRy, kRz).
inline constexpr int kMotionErrors = 18;

template <typename T>
void MotionErrors(const AxisChain& chain, const T* e, const Eigen::Matrix<T, 3, 1>& q, T* motion) {
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) {
      motion[6 * k + c] = e[TranslationTerm(static_cast<Axis>(k), c)];
      motion[6 * k + 3 + c] = e[RotationTerm(static_cast<Axis>(k), c)];
    }
  }
  for (int w = 0; w < 3; ++w) {
    const int k = static_cast<int>(chain.squareness_carrier[static_cast<size_t>(w)]);
    const ErrorTerm& term = GetErrorTerm(kFirstSquarenessTerm + w);
    const int other = static_cast<int>(term.axis) == k ? term.component : static_cast<int>(term.axis);
    motion[6 * k + other] -= q[k] * e[kFirstSquarenessTerm + w];
  }
}

// Part coordinates of the tool point commanded to q, given the motion errors of the axes (MotionErrors).
// instrument_pose6 (translation, rotation vector) overrides chain.instrument, so a solver can estimate it.
template <typename T>
Eigen::Matrix<T, 3, 1> ChainForwardFromMotions(const AxisChain& chain, const T* motion, const Eigen::Matrix<T, 3, 1>& q,
                                               const T* instrument_pose6 = nullptr) {
  using internal::Vec3;
  Vec3<T> w = chain.tool_offset.template cast<T>();
  for (auto it = chain.tool_axes.rbegin(); it != chain.tool_axes.rend(); ++it) {
    w = internal::AxisTranslation(chain, *it, motion, q) +
        internal::Rotate(chain.rotation_model, internal::AxisRotation(*it, motion), w);
  }
  for (Axis axis : chain.part_axes) {
    w = internal::RotateInverse(chain.rotation_model, internal::AxisRotation(axis, motion),
                                Vec3<T>(w - internal::AxisTranslation(chain, axis, motion, q)));
  }
  if (instrument_pose6 != nullptr) return ToPosedFrame(instrument_pose6, w);
  if (chain.instrument) {
    const Pose& pose = *chain.instrument;
    const T pose6[6] = {T(pose.translation[0]), T(pose.translation[1]), T(pose.translation[2]),
                        T(pose.rotation[0]),    T(pose.rotation[1]),    T(pose.rotation[2])};
    return ToPosedFrame(pose6, w);
  }
  return w;
}

// The tool's orientation in the part frame: d(part coordinates) / d(tool offset), i.e. the rotations of
// ChainForwardFromMotions without its translations (instrument pose excluded). For a microscope this is how the
// camera sees the part: a vector in the camera's frame shows up as C v in the part frame. With `inverse`, C^-1,
// by the inverse rotations in reverse order (exact for both rotation models, no matrix inverse).
template <typename T>
Eigen::Matrix<T, 3, 3> ChainOrientation(const AxisChain& chain, const T* motion, bool inverse = false) {
  using internal::Vec3;
  Eigen::Matrix<T, 3, 3> c;
  for (int k = 0; k < 3; ++k) {
    Vec3<T> w = Vec3<T>::Zero();
    w[k] = T(1.0);
    if (!inverse) {
      for (auto it = chain.tool_axes.rbegin(); it != chain.tool_axes.rend(); ++it) {
        w = internal::Rotate(chain.rotation_model, internal::AxisRotation(*it, motion), w);
      }
      for (Axis axis : chain.part_axes) w = internal::RotateInverse(chain.rotation_model, internal::AxisRotation(axis, motion), w);
    } else {
      for (auto it = chain.part_axes.rbegin(); it != chain.part_axes.rend(); ++it) {
        w = internal::Rotate(chain.rotation_model, internal::AxisRotation(*it, motion), w);
      }
      for (Axis axis : chain.tool_axes) w = internal::RotateInverse(chain.rotation_model, internal::AxisRotation(axis, motion), w);
    }
    c.col(k) = w;
  }
  return c;
}

// Part coordinates of the tool point commanded to q, given the values e[0..20] of the 21 error terms at q.
template <typename T>
Eigen::Matrix<T, 3, 1> ChainForward(const AxisChain& chain, const T* e, const Eigen::Matrix<T, 3, 1>& q,
                                    const T* instrument_pose6 = nullptr) {
  T motion[kMotionErrors];
  MotionErrors(chain, e, q, motion);
  return ChainForwardFromMotions(chain, motion, q, instrument_pose6);
}

}  // namespace fvm::stage
