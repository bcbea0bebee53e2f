#pragma once
// The observation model of the identification (stage/identification.h): where the model puts each observation
// (a point, or a displacement between two registered tiles), seen in its stitched frame and through the
// instrument's pose, whitened by its covariance, with the Jacobians the solver and the rank treatment need.
// Internal to the identification and its Monte Carlo; not a public interface.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

#include "stage/axis_chain.h"
#include "stage/identification.h"
#include "stage/parameter_layout.h"
#include "stage/pose.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

using SparseTermDerivative = std::vector<ParameterLayout::TermDerivativeEntry>;

// Plausible sizes of the instrument pose's corrections: 1 mm of translation, 1 mrad of rotation. They scale the
// solver's pose parameters as PlausibleSizes does the coefficients.
inline constexpr double kPoseTranslationSize = 1.0;
inline constexpr double kPoseRotationSize = 1e-3;
inline constexpr int kPoseParameters = 6;

// Machine-frame point of the tool at one command and, optionally, its Jacobian w.r.t. the free coefficients
// (3 x n): Jets through the chain for the 21 term values, then the exact linear map to the coefficients.
// `all` holds every coefficient's value (ParameterLayout::Expand), expanded once per evaluation, not per point.
Eigen::Vector3d EvaluatePoint(const ParameterLayout& layout, const AxisChain& chain, const double* all,
                              const Eigen::Vector3d& q, const SparseTermDerivative& derivative, Eigen::Matrix3Xd* jacobian);

// The map from the part frame into the instrument's: identity, or R^T (p - t) at a pose.
class InstrumentMap {
 public:
  InstrumentMap() : InstrumentMap(std::array<double, kPoseParameters>{}.data()) { active_ = false; }
  explicit InstrumentMap(const double* pose6);
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const {
    return active_ ? Eigen::Vector3d(rotation_transposed_ * (p - Eigen::Vector3d(pose6_[0], pose6_[1], pose6_[2]))) : p;
  }
  // d(instrument coordinates) / d(part coordinates).
  Eigen::Matrix3d Linear() const { return active_ ? rotation_transposed_ : Eigen::Matrix3d::Identity(); }
  // d(instrument coordinates) / d(pose6) at part-frame point p: ToPosedFrame's derivative, from the derivatives
  // taken once at the axes' unit vectors (R^T (p - t) is linear in p - t).
  Eigen::Matrix<double, 3, kPoseParameters> PoseJacobian(const Eigen::Vector3d& p) const;

 private:
  bool active_ = false;
  std::array<double, kPoseParameters> pose6_{};
  Eigen::Matrix3d rotation_transposed_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d translation_derivative_ = -Eigen::Matrix3d::Identity();  // d/dt: -R^T
  std::array<Eigen::Matrix3d, 3> rotation_derivative_{};  // [j]: d(R^T e_j) / d(rotation vector)
};

struct PreparedObservation {
  Eigen::Vector3d command;
  Eigen::Vector3d measured;
  SparseTermDerivative derivative;
  int anchor = -1;                  // index into the prepared anchors, or -1
  const AxisChain* chain = nullptr;  // the layout's chain with this observation's tool offset
  Eigen::Matrix3d whiten = Eigen::Matrix3d::Identity();  // L^-1 of its covariance L L^T; identity: equal weights
  Eigen::Matrix3d colour = Eigen::Matrix3d::Identity();  // L: back from whitened residuals to millimetres
  int components = 3;                                    // observed coordinates (Whitening)
  std::optional<Eigen::Vector3d> from;                   // a displacement's start (Observation::from)
  SparseTermDerivative from_derivative;
};

struct PreparedAnchor {
  Eigen::Vector3d position;
  SparseTermDerivative derivative;
};

struct Prepared {
  std::vector<AxisChain> chains;  // one per tool offset
  std::vector<PreparedObservation> observations;
  std::vector<PreparedAnchor> anchors;
  StitchedFrame frame = StitchedFrame::kTranslated;
  std::optional<Eigen::Vector3d> frame_reference;  // r of the turn C(a)^-1 C(r): the first anchor
  bool weighted = false;
  bool estimate_pose = false;
  std::array<double, kPoseParameters> pose6{};  // held pose, or where the estimated one starts
  bool has_pose = false;
  Eigen::Matrix<double, kPoseParameters, 1> pose_scale;
  int threads = 1;  // Linearise's threads (IdentificationOptions::num_threads; 0: all cores)
};

// The stitched frame of one anchored measurement at the current coefficients (stitched_frame.h): a point the
// model puts at P is seen at first_tile + turn (P - origin).
struct AnchorFrame {
  Eigen::Vector3d first_tile = Eigen::Vector3d::Zero();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // F(a)
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  Eigen::Matrix3Xd origin_jacobian;                  // dF(a) / d(free), 3 x n, when derivatives are wanted
  std::vector<Eigen::Matrix3d> turn_jacobian;        // dT / d(free k); empty when the turn is held (translated)
};

AnchorFrame EvaluateAnchor(const ParameterLayout& layout, const AxisChain& chain, const double* free, const double* all,
                           const Prepared& p, const PreparedAnchor& a, bool want_jacobian);

// The residual of one observation, whitened, and its Jacobians w.r.t. the free coefficients (unscaled) and the
// pose (unscaled, when estimated). `anchor`: the stitched frame of its placement, or null (the model's P itself).
Eigen::Vector3d ObservationResidual(const ParameterLayout& layout, const double* free, const double* all,
                                    const Prepared& p, const InstrumentMap& instrument, const PreparedObservation& o,
                                    const AnchorFrame* anchor, Eigen::Matrix3Xd* jacobian,
                                    Eigen::Matrix<double, 3, kPoseParameters>* pose_jacobian);

// Stacked (whitened) residuals and, unless `jacobian` is null, their Jacobian (unscaled) at the given
// coefficients and pose: the free coefficients' columns, then the pose's six when it is estimated.
void Linearise(const ParameterLayout& layout, const std::vector<double>& free, const double* pose6, const Prepared& p,
               Eigen::VectorXd* residual, Eigen::MatrixXd* jacobian);

// The observations and options prepared once for every evaluation: chains per tool, term derivatives, whitening.
// Throws std::invalid_argument naming an observation whose covariance is not positive definite.
Prepared Prepare(const ParameterLayout& layout, const std::vector<Observation>& observations,
                 const IdentificationOptions& options);

// `p`, prepared for `before`, made what Prepare gives for `after`: the same layout with some free coefficients
// fixed (the rank treatment's). Their derivative entries go, the others move to their new slots; the values are
// the ones Prepare computes, without evaluating every basis and whitening every observation again.
void Reslot(Prepared& p, const ParameterLayout& before, const ParameterLayout& after);

}  // namespace fvm::stage
