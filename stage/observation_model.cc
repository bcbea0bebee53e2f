#include "stage/observation_model.h"

#include <ceres/jet.h>
#include <fmt/core.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

#include "core/dense_decomposition.h"

namespace fvm::stage {
namespace {

// L^-1 of a covariance L L^T, so that |L^-1 r|^2 is the Mahalanobis distance of r, and L. A coordinate of infinite
// variance is not observed: its rows and columns of both stay zero, and it counts no equation.
struct Whitened {
  Eigen::Matrix3d whiten = Eigen::Matrix3d::Zero(), colour = Eigen::Matrix3d::Zero();
  int components = 0;
};
Whitened Whitening(const Eigen::Matrix3d& covariance, int index) {
  const auto not_positive = [&] {
    return std::invalid_argument(fmt::format("observation {}: its covariance is not positive definite", index + 1));
  };
  if (!covariance.diagonal().array().isInf().any()) {
    // Every coordinate observed (a tracker's reading): the same factors as below, on a fixed-size matrix.
    if (!covariance.allFinite()) throw not_positive();
    const auto llt = Decompose<Eigen::LLT<Eigen::Matrix3d>>(covariance, "the covariance of an observation");
    if (llt.info() != Eigen::Success) throw not_positive();
    Whitened w;
    w.colour = llt.matrixL();
    w.whiten = w.colour.triangularView<Eigen::Lower>().solve(Eigen::Matrix3d::Identity());
    w.components = 3;
    return w;
  }
  std::vector<int> observed;
  for (int c = 0; c < 3; ++c) {
    if (!std::isinf(covariance(c, c))) observed.push_back(c);
  }
  const Eigen::Index k = static_cast<Eigen::Index>(observed.size());
  Eigen::MatrixXd block(k, k);
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) block(a, b) = covariance(observed[static_cast<size_t>(a)], observed[static_cast<size_t>(b)]);
  }
  bool crossed = false;  // an unobserved coordinate must not covary with an observed one
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) crossed = crossed || (a != b && std::isinf(covariance(a, a)) && covariance(a, b) != 0.0);
  }
  if (k == 0 || !block.allFinite() || crossed) throw not_positive();
  const auto llt = Decompose<Eigen::LLT<Eigen::MatrixXd>>(block, fmt::format("the covariance of observation {}", index + 1));
  if (llt.info() != Eigen::Success) throw not_positive();
  const Eigen::MatrixXd l = llt.matrixL();
  const Eigen::MatrixXd l_inverse = l.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(k, k));
  Whitened w;
  w.components = static_cast<int>(k);
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) {
      w.whiten(observed[static_cast<size_t>(a)], observed[static_cast<size_t>(b)]) = l_inverse(a, b);
      w.colour(observed[static_cast<size_t>(a)], observed[static_cast<size_t>(b)]) = l(a, b);
    }
  }
  return w;
}

}  // namespace

Eigen::Matrix3d ObservedInformation(const Eigen::Matrix3d& covariance, int index) {
  const Whitened w = Whitening(covariance, index);
  return w.whiten.transpose() * w.whiten;
}

InstrumentMap::InstrumentMap(const double* pose6) : active_(true) {
  std::copy(pose6, pose6 + kPoseParameters, pose6_.begin());
  rotation_transposed_ =
      Pose{Eigen::Vector3d(pose6[0], pose6[1], pose6[2]), Eigen::Vector3d(pose6[3], pose6[4], pose6[5])}.Rotation().transpose();
  // ToPosedFrame rotates p - t by the rotation vector's negative; differentiated at each unit vector, once.
  using Jet = ceres::Jet<double, 3>;
  const Jet minus[3] = {-Jet(pose6[3], 0), -Jet(pose6[4], 1), -Jet(pose6[5], 2)};
  for (int axis = 0; axis < 3; ++axis) {
    Jet unit[3] = {Jet(0.0), Jet(0.0), Jet(0.0)};
    unit[axis] = Jet(1.0);
    Jet out[3];
    ceres::AngleAxisRotatePoint(minus, unit, out);
    for (int r = 0; r < 3; ++r) {
      translation_derivative_(r, axis) = -out[r].a;
      rotation_derivative_[static_cast<size_t>(axis)].row(r) = out[r].v.transpose();
    }
  }
}

Eigen::Matrix<double, 3, kPoseParameters> InstrumentMap::PoseJacobian(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d shifted = p - Eigen::Vector3d(pose6_[0], pose6_[1], pose6_[2]);
  Eigen::Matrix<double, 3, kPoseParameters> j;
  j.leftCols<3>() = translation_derivative_;
  j.rightCols<3>() = shifted[0] * rotation_derivative_[0] + shifted[1] * rotation_derivative_[1] + shifted[2] * rotation_derivative_[2];
  return j;
}

// Machine-frame point of the tool at one command and, optionally, its Jacobian w.r.t. the free coefficients
// (3 x n): Jets through the chain for the 21 term values, then the exact linear map to the coefficients.
// `all` holds every coefficient's value (ParameterLayout::Expand), expanded once per evaluation, not per point.
Eigen::Vector3d EvaluatePoint(const ParameterLayout& layout, const AxisChain& chain, const double* all,
                              const Eigen::Vector3d& q, const SparseTermDerivative& derivative, Eigen::Matrix3Xd* jacobian) {
  double e[kNumErrorTerms];
  layout.TermValues(all, q, e);
  if (jacobian == nullptr) return ChainForward(chain, e, q);
  Eigen::Vector3d p;
  const Eigen::Matrix<double, 3, kNumErrorTerms> term_jacobian = TermJacobian(chain, e, q, &p, layout.AxesWithErrors());
  jacobian->setZero(3, layout.NumFree());
  for (const ParameterLayout::TermDerivativeEntry& d : derivative) jacobian->col(d.slot) += term_jacobian.col(d.term) * d.value;
  return p;
}

AnchorFrame EvaluateAnchor(const ParameterLayout& layout, const AxisChain& chain, const double* free, const double* all,
                           const Prepared& p, const PreparedAnchor& a, bool want_jacobian) {
  AnchorFrame f;
  f.first_tile = a.position;
  f.origin = EvaluatePoint(layout, chain, all, a.position, a.derivative, want_jacobian ? &f.origin_jacobian : nullptr);
  if (p.frame == StitchedFrame::kRotated) {
    f.turn = FirstTileTurn(p.frame, layout, free, a.position, p.frame_reference ? &*p.frame_reference : nullptr,
                           want_jacobian ? &f.turn_jacobian : nullptr);
  }
  return f;
}

// The residual of one observation, whitened, and its Jacobians w.r.t. the free coefficients (unscaled) and the
// pose (unscaled, when estimated). `anchor`: the stitched frame of its placement, or null (the model's P itself).
Eigen::Vector3d ObservationResidual(const ParameterLayout& layout, const double* free, const double* all,
                                    const Prepared& p, const InstrumentMap& instrument, const PreparedObservation& o,
                                    const AnchorFrame* anchor, Eigen::Matrix3Xd* jacobian,
                                    Eigen::Matrix<double, 3, kPoseParameters>* pose_jacobian) {
  thread_local Eigen::Matrix3Xd j;  // kept between calls: one allocation per thread, not one per observation
  Eigen::Vector3d part = EvaluatePoint(layout, *o.chain, all, o.command, o.derivative, jacobian ? &j : nullptr);
  if (o.from) {
    // A displacement seen in the camera's frame: T (F(b) - F(a)) with T the mean turn of its two ends. The overlap
    // of two registered tiles lies midway between their centres, where the camera's orientation is the mean of
    // theirs to first order.
    Eigen::Matrix3Xd ja;
    const Eigen::Vector3d start = EvaluatePoint(layout, *o.chain, all, *o.from, o.from_derivative, jacobian ? &ja : nullptr);
    const Eigen::Vector3d move = part - start;
    const Eigen::Vector3d* reference = p.frame_reference ? &*p.frame_reference : nullptr;
    std::vector<Eigen::Matrix3d> ta_j, tb_j;
    const Eigen::Matrix3d ta = FirstTileTurn(p.frame, layout, free, *o.from, reference, jacobian ? &ta_j : nullptr);
    const Eigen::Matrix3d tb = FirstTileTurn(p.frame, layout, free, o.command, reference, jacobian ? &tb_j : nullptr);
    const Eigen::Matrix3d turn = 0.5 * (ta + tb);
    part = turn * move;
    if (jacobian) {
      j = turn * (j - ja);
      for (size_t k = 0; k < ta_j.size(); ++k) j.col(static_cast<Eigen::Index>(k)) += 0.5 * (ta_j[k] + tb_j[k]) * move;
    }
  } else if (anchor) {
    const Eigen::Vector3d arm = part - anchor->origin;
    part = anchor->first_tile + anchor->turn * arm;
    if (jacobian) {
      j = anchor->turn * (j - anchor->origin_jacobian);
      for (size_t k = 0; k < anchor->turn_jacobian.size(); ++k) j.col(static_cast<Eigen::Index>(k)) += anchor->turn_jacobian[k] * arm;
    }
  }
  if (jacobian) *jacobian = o.whiten * instrument.Linear() * j;
  if (pose_jacobian) *pose_jacobian = o.whiten * instrument.PoseJacobian(part);
  return o.whiten * (instrument.Apply(part) - o.measured);
}

Prepared Prepare(const ParameterLayout& layout, const std::vector<Observation>& observations,
                 const IdentificationOptions& options) {
  Prepared p;
  if (options.tool_offsets.empty()) {
    p.chains.push_back(layout.chain());
  } else {
    for (const Eigen::Vector3d& tool : options.tool_offsets) {
      p.chains.push_back(layout.chain());
      p.chains.back().tool_offset = tool;
    }
  }
  if (options.anchor == Anchor::kFirstTile) {
    for (const Eigen::Vector3d& a : options.anchors) p.anchors.push_back({a, layout.TermDerivativeEntries(a)});
  }
  p.frame = options.frame;
  if (!options.anchors.empty()) p.frame_reference = options.anchors.front();
  for (const Observation& o : observations) p.weighted = p.weighted || !o.covariance.isZero(0.0);
  p.observations.reserve(observations.size());
  for (size_t i = 0; i < observations.size(); ++i) {
    const Observation& o = observations[i];
    PreparedObservation po;
    po.command = o.command;
    po.measured = o.measured;
    po.derivative = layout.TermDerivativeEntries(o.command);
    po.chain = &p.chains[static_cast<size_t>(o.tool)];
    if (options.anchor == Anchor::kFirstTile && !o.from) po.anchor = o.group;
    if (o.from) {
      po.from = o.from;
      po.from_derivative = layout.TermDerivativeEntries(*o.from);
    }
    if (p.weighted) {
      const Whitened w = Whitening(o.covariance, static_cast<int>(i));
      po.whiten = w.whiten;
      po.colour = w.colour;
      po.components = w.components;
    }
    p.observations.push_back(std::move(po));
  }
  p.has_pose = options.instrument != InstrumentPose::kNone;
  p.estimate_pose = options.instrument == InstrumentPose::kEstimated;
  const Eigen::Vector3d& t = options.pose.translation;
  const Eigen::Vector3d& r = options.pose.rotation;
  p.pose6 = {t[0], t[1], t[2], r[0], r[1], r[2]};
  p.pose_scale << kPoseTranslationSize, kPoseTranslationSize, kPoseTranslationSize, kPoseRotationSize, kPoseRotationSize,
      kPoseRotationSize;
  p.threads = options.num_threads;
  return p;
}

void Reslot(Prepared& p, const ParameterLayout& before, const ParameterLayout& after) {
  std::vector<int> slot;  // new slot of each old one, -1 when fixed now
  for (const std::string& name : before.FreeNames()) slot.push_back(after.FreeIndexOf(name));
  const auto move = [&](SparseTermDerivative& d) {
    std::erase_if(d, [&](const ParameterLayout::TermDerivativeEntry& e) { return slot[static_cast<size_t>(e.slot)] < 0; });
    for (ParameterLayout::TermDerivativeEntry& e : d) e.slot = slot[static_cast<size_t>(e.slot)];
  };
  for (PreparedObservation& o : p.observations) {
    move(o.derivative);
    move(o.from_derivative);
  }
  for (PreparedAnchor& a : p.anchors) move(a.derivative);
}

// Stacked (whitened) residuals and, unless `jacobian` is null, their Jacobian (unscaled) at the given
// coefficients and pose: the free coefficients' columns, then the pose's six when it is estimated.
void Linearise(const ParameterLayout& layout, const std::vector<double>& free, const double* pose6, const Prepared& p,
               Eigen::VectorXd* residual, Eigen::MatrixXd* jacobian) {
  const Eigen::Index m = static_cast<Eigen::Index>(p.observations.size());
  const Eigen::Index n = layout.NumFree();
  std::array<double, kMaxCoefficients> all{};
  layout.Expand(free.data(), all.data());
  const InstrumentMap instrument = p.has_pose ? InstrumentMap(pose6) : InstrumentMap();
  residual->resize(3 * m);
  if (jacobian) jacobian->resize(3 * m, n + (p.estimate_pose ? kPoseParameters : 0));
  std::vector<AnchorFrame> anchors;
  for (const PreparedAnchor& a : p.anchors) {
    anchors.push_back(EvaluateAnchor(layout, p.chains.front(), free.data(), all.data(), p, a, jacobian != nullptr));
  }
  // Each observation fills its own rows: in parallel, the same numbers as in turn.
  const auto evaluate = [&](Eigen::Index begin, Eigen::Index end) {
    Eigen::Matrix3Xd j;
    Eigen::Matrix<double, 3, kPoseParameters> pose_j;
    for (Eigen::Index i = begin; i < end; ++i) {
      const PreparedObservation& o = p.observations[static_cast<size_t>(i)];
      residual->segment<3>(3 * i) = ObservationResidual(
          layout, free.data(), all.data(), p, instrument, o, o.anchor >= 0 ? &anchors[static_cast<size_t>(o.anchor)] : nullptr,
          jacobian ? &j : nullptr, jacobian && p.estimate_pose ? &pose_j : nullptr);
      if (!jacobian) continue;
      jacobian->block(3 * i, 0, 3, n) = j;
      if (p.estimate_pose) jacobian->block<3, kPoseParameters>(3 * i, n) = pose_j;
    }
  };
  constexpr Eigen::Index kChunk = 512;  // observations per task: a few per thread on tracker meshes of thousands
  if (p.threads == 1 || m < 2 * kChunk) return evaluate(0, m);
  tbb::task_arena arena(p.threads > 0 ? p.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, kChunk),
                      [&](const tbb::blocked_range<Eigen::Index>& r) { evaluate(r.begin(), r.end()); });
  });
}

}  // namespace fvm::stage
