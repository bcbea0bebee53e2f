#pragma once
// The field's cubic terms chosen by the overlaps' evidence (the discrepancy workflow applied to the field): start from
// what an objective's optics give at low order, add what the overlaps show beyond it.
//
// The third-order distortion of a rotationally symmetric objective is radial, k1 (x, y) r^2 (Seidel; Brown 1966,
// after Conrady 1919); decentring and thin-prism errors enter at second order (Brown 1966; Weng, Cohen, Herniou
// 1992). A cubic departure from radial symmetry in the own-axis terms (x^3 in dx not matched by x y^2 in dx, y^3 in
// dy not matched by x^2 y in dy, or a different k1 along x and y) has no low-order optical source in a widefield
// objective (a galvo-scanning confocal has one). It matters because a chain of tiles sees the own-axis terms only
// through the curvature of the step across the thin overlap band (field_distortion.h, kHeldStretchTerms): free, they
// are the least determined terms of the field (0.003 px a term on scangen's 402-tile scans, 20 % overlap) and act
// on the mosaic as a scale; tied to the cross terms by radial symmetry, they are pinned through x y^2 and x^2 y,
// which every overlap sees across its whole length (0.0003 px).
//
// So the field is solved first with every term (FitFieldDistortion); the terms that depart from radial symmetry in
// the own-axis cubic (kNonRadialOwnAxisCubic: dx_x3, dx_xy2 and dy_x2y in FieldDistortionTermNames' basis, where
// x^3 in dx is k1 + dx_x3, x y^2 in dx k1 + dx_xy2, x^2 y in dy k1 + dy_x2y and y^3 in dy k1) are then tested
// jointly by their Wald statistic c^T Cov^-1 c against the Bayesian information criterion's price of 3 terms,
// 3 ln(number of residuals) (Schwarz 1978): below it, the overlaps do not show them and they are held at 0 (the
// field radial in its cubic own-axis part; every other term stays free); above it, they stay. The result names them
// either way (FieldDistortionFit::tested_terms, tested_terms_added).

#include <Eigen/Core>
#include <vector>

#include "imaging/field_distortion_fit.h"

namespace fvm::imaging {

inline constexpr const char* kNonRadialOwnAxisCubic =
    "the cubic terms that depart from radial symmetry in the own-axis part (x^3 in dx beyond x y^2, y^3 in dy beyond "
    "x^2 y, a different k1 along x and y) have no low-order optical source in a widefield objective and the "
    "overlaps did not show them (Wald statistic below 3 ln n): held at 0, so the radial k1 carries x^3 and y^3";

// The indices of dx_x3, dx_xy2, dy_x2y in FieldDistortionTermNames(order); empty below order 3.
std::vector<int> FieldDistortionNonRadialOwnAxisTerms(int order);

// FitFieldDistortion with the non-radial own-axis cubic terms added only when the overlaps show them (above). For
// a known field, an order below 3, or options that already hold terms, the same as FitFieldDistortion.
FieldDistortionFit FitFieldDistortionByEvidence(const std::vector<PairCorrespondences>& pairs,
                                                const std::vector<Eigen::Vector2d>& initial_px,
                                                const std::vector<bool>& fixed, int width_px, int height_px,
                                                const FieldDistortionFitOptions& options);

}  // namespace fvm::imaging
