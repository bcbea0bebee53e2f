#include "imaging/field_distortion_evidence.h"
#include "core/dense_decomposition.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>

namespace fvm::imaging {

std::vector<int> FieldDistortionNonRadialOwnAxisTerms(int order) {
  if (order < 3) return {};
  const std::vector<std::string>& names = FieldDistortionTermNames(order);
  std::vector<int> out;
  for (const char* name : {"dx_x3", "dx_xy2", "dy_x2y"}) {
    const auto at = std::find(names.begin(), names.end(), name);
    if (at == names.end()) return {};  // another basis: nothing to test
    out.push_back(static_cast<int>(at - names.begin()));
  }
  return out;
}

FieldDistortionFit FitFieldDistortionByEvidence(const std::vector<PairCorrespondences>& pairs,
                                                const std::vector<Eigen::Vector2d>& initial_px,
                                                const std::vector<bool>& fixed, int width_px, int height_px,
                                                const FieldDistortionFitOptions& options) {
  FieldDistortionFit full = FitFieldDistortion(pairs, initial_px, fixed, width_px, height_px, options);
  const std::vector<int> tested = FieldDistortionNonRadialOwnAxisTerms(options.order);
  if (tested.empty() || options.hold_stretch_terms || !options.hold_terms.empty()) return full;
  const auto n = static_cast<Eigen::Index>(tested.size());
  Eigen::VectorXd c(n);
  Eigen::MatrixXd cov(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    c(r) = full.field.coefficients(tested[static_cast<size_t>(r)]);
    for (Eigen::Index s = 0; s < n; ++s) cov(r, s) = full.field.covariance(tested[static_cast<size_t>(r)], tested[static_cast<size_t>(s)]);
  }
  const double chi2 = c.dot(Decompose<Eigen::LDLT<Eigen::MatrixXd>>(cov, "the non-radial own-axis cubic terms' covariance").solve(c));
  const double threshold = static_cast<double>(n) * std::log(2.0 * std::max(full.points, 1));
  const auto named = [&](FieldDistortionFit fit, bool added) {
    fit.tested_terms = tested, fit.tested_terms_added = added;
    fit.evidence_chi2 = chi2, fit.evidence_threshold = threshold;
    return fit;
  };
  if (chi2 > threshold) return named(std::move(full), true);
  FieldDistortionFitOptions radial = options;
  radial.hold_terms = tested;
  radial.hold_reason = kNonRadialOwnAxisCubic;
  return named(FitFieldDistortion(pairs, initial_px, fixed, width_px, height_px, radial), false);
}

}  // namespace fvm::imaging
