#pragma once
// The field distortion (field_distortion.h) and the tile positions identified together from the overlaps: every
// correspondence of every overlap (overlap_correspondences.h) says that two raw pixels see one point,
//   p_a + u_a + d(u_a) = p_b + u_b + d(u_b),
// linear in the positions p and the coefficients of d, with d averaged over the window each point was matched on
// (PairCorrespondences::kernel, FieldKernel): read at the windows' centres, a radial field's curvature passed for a
// scale of every step. One Ceres problem holds them all, each residual scaled by
// the correspondences' own scatter and robust (Huber) against the few that tracked the wrong speckle; the
// covariance of positions and coefficients is the inverse of that problem's information, so that the positions
// carry the field's uncertainty. The published method (Rouwane, Texier, Passieux 2024) identifies the field by
// dense image correlation alone, without one.
//
// What the overlaps cannot determine is refused, by name, before anything is solved: the linear part always
// (kFixedLinearPart), and terms that only one direction of overlaps leaves unseen (a strip of tiles in a row sees
// how d changes along x, never a term in y alone) or that the overlap's thin band cannot pin over the whole tile
// (too high an order).

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "imaging/field_distortion.h"
#include "imaging/overlap_correspondences.h"

namespace fvm::imaging {

// The overlaps cannot determine the terms `what` names; its message says why and what to do.
class FieldDistortionUndeterminable : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct FieldDistortionFitOptions {
  int order = 3;  // FieldDistortionTermNames(order); 2..kMaxDistortionOrder (the workflows set it from theirs)
  // The field must come out within this (px, standard uncertainty of d rms over the tile, of each term's share
  // of it): a term that the overlaps pin less well is refused by name.
  double max_field_sigma_px = 0.5;
  // Pairs with fewer correspondences than this carry no weight (a texture-free overlap).
  int min_pair_points = 12;
  double huber_sigmas = 2.0;  // the robust loss's bend, in the correspondences' standard deviations
  // Hold the terms that act on the overlaps as a stretch or shear of the mosaic (FieldDistortionStretchTerms,
  // kHeldStretchTerms) at 0: what a stitched grid needs, where nothing but the overlaps places the tiles.
  bool hold_stretch_terms = false;
  // Terms held at 0 besides those (indices into FieldDistortionTermNames(order)), for the reason `hold_reason` says
  // (FitFieldDistortionByEvidence).
  std::vector<int> hold_terms;
  std::string hold_reason;
  int threads = 2;  // Ceres' threads for the solve (fvm stitch sets its --threads)
  void Check() const;  // throws std::invalid_argument
};

struct FieldDistortionFit {
  FieldDistortion field;
  std::vector<Eigen::Vector2d> positions_px;   // of the undistorted tiles
  // Against the fixed tiles; the positions' and the field's covariance are widened as pair_scatter_factor and
  // block_scatter_factor say and carry a registered pair's floor (0.005 px) shared by all points of an overlap.
  std::vector<Eigen::Matrix2d> position_covariance_px2;
  double point_sigma_px = 0.0;   // robust scatter of one correspondence about the model (per axis)
  double rigid_rms_px = 0.0;     // rms of the correspondences' residuals at the start (the rigid positions, d = 0)
  double residual_rms_px = 0.0;  // ... and with the field and positions found (inliers within 3 sigma)
  // How much more the pairs' mean residuals scatter than the points' own scatter allows (the model's misfit is
  // shared by the points of a pair): 1 when they do not, or no loop checks them ...
  double pair_scatter_factor = 1.0;
  // ... and the quarters of each overlap's band about their pair's mean (the points of one overlap share errors at
  // that scale, which move the field's terms and which no loop checks). The covariance (field and positions) is
  // scaled up by the larger of the two.
  double block_scatter_factor = 1.0;
  int block_dof = 0;  // the blocks' degrees of freedom behind block_scatter_factor (2 x 3 a pair)
  int points = 0, pairs_used = 0, pairs_without_texture = 0;
  int iterations = 0;
  std::vector<int> held_terms;  // held at 0 (hold_stretch_terms, hold_terms): value and u 0
  std::string held_reason;      // why (kHeldStretchTerms or the options' hold_reason)
  // FitFieldDistortionByEvidence: the terms it tested, whether the overlaps showed them (then solved, else held), its
  // Wald statistic and the threshold it was held against.
  std::vector<int> tested_terms;
  bool tested_terms_added = false;
  double evidence_chi2 = 0.0, evidence_threshold = 0.0;
  std::string solver_report;  // Ceres' BriefReport of the last solve
};

// `pairs`: correspondences of each overlap (tile indices into `initial_px`); `fixed`: tiles whose positions hold
// (the first tile of each connected group, tiles no pair reaches). Throws FieldDistortionUndeterminable when no pair
// has texture, or when terms cannot be determined (naming them), std::invalid_argument for inconsistent input.
// `known`: a field identified before (the same objective): held as it is, only the positions solved (its
// covariance, when it has one, is not propagated: the positions' u are those of the overlaps alone).
FieldDistortionFit FitFieldDistortion(const std::vector<PairCorrespondences>& pairs,
                                      const std::vector<Eigen::Vector2d>& initial_px, const std::vector<bool>& fixed,
                                      int width_px, int height_px, const FieldDistortionFitOptions& options,
                                      const FieldDistortion* known = nullptr);

}  // namespace fvm::imaging
