#include "stage/discrepancy_scoring.h"

#include <fmt/core.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "core/dense_decomposition.h"
#include "stage/axis_chain.h"

namespace fvm::stage {

Eigen::VectorXd Stack(const std::vector<Eigen::Vector3d>& v) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out.segment<3>(3 * static_cast<Eigen::Index>(i)) = v[i];
  return out;
}

// d(residual)/d(coefficients named) for every observation, columns scaled to unit norm (the F-test and the
// rank decisions do not depend on units).
Eigen::MatrixXd CoefficientColumns(const ParameterLayout& layout, const std::vector<double>& values,
                                   const std::vector<std::string>& names, const MeasurementSet& set, bool anchored) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()),
                                                  static_cast<Eigen::Index>(names.size()));
  std::vector<Eigen::MatrixXd> anchor_jacobians;
  for (const Eigen::Vector3d& a : set.anchors) anchor_jacobians.push_back(ForwardJacobian(layout, values.data(), a));
  for (size_t i = 0; i < set.observations.size(); ++i) {
    Eigen::MatrixXd j = ForwardJacobian(layout, values.data(), set.observations[i].command);
    if (anchored) j -= anchor_jacobians[static_cast<size_t>(set.observations[i].group)];
    for (size_t c = 0; c < names.size(); ++c) {
      columns.block<3, 1>(3 * static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) = j.col(layout.FreeIndexOf(names[c]));
    }
  }
  return columns;
}

std::vector<double> ValuesByName(const ParameterLayout& from, const std::vector<double>& values, const ParameterLayout& to) {
  std::vector<double> out;
  for (const std::string& name : to.FreeNames()) {
    const int slot = from.FreeIndexOf(name);
    out.push_back(slot >= 0 ? values[static_cast<size_t>(slot)] : 0.0);
  }
  return out;
}



// Extra sum of squares of the candidate columns over the base model, on the linearised problem.
//
// Only the part of a candidate that the base model leaves above 1 % of its norm counts as new. Below that, its
// estimate would rest on what the model does not describe rather than on the effect: a scale about a shared start
// is the model's linear terms xTx1 and yTy1 but for the noise, the bar's pitch errors and the stage's own
// non-polynomial error in the stitched coordinates it is built from (about 1e-4 of them), and fitted to that
// remainder it comes out at 1e6 ppm.
LinearScore ScoreColumns(const Eigen::VectorXd& r0, const Eigen::MatrixXd& base, const Eigen::MatrixXd& extra,
                         std::string_view candidate) {
  constexpr double kNewDirection = 1e-2;
  LinearScore s;
  s.rows = static_cast<double>(r0.size());
  Eigen::MatrixXd all(base.rows(), base.cols() + extra.cols());
  all << base, extra;
  Eigen::VectorXd norms = all.colwise().norm();
  for (Eigen::Index c = 0; c < all.cols(); ++c) {
    if (norms[c] > 0) all.col(c) /= norms[c];
  }
  const std::string what = fmt::format("the discrepancy scoring of candidate {}", candidate);
  RequireFiniteMatrix(r0, what + " (the residuals)");
  // A base model with every parameter fixed (a gross outlier makes them all look undetermined) has no columns:
  // nothing of the residuals is its.
  int base_rank = 0;
  Eigen::MatrixXd q_base(all.rows(), 0);
  if (base.cols() > 0) {
    auto base_qr =
        Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(all.leftCols(base.cols()), what + " (the base model's columns)");
    base_qr.setThreshold(1e-9);
    base_rank = static_cast<int>(base_qr.rank());
    q_base = Eigen::MatrixXd(base_qr.householderQ()).leftCols(base_rank);
  }
  const Eigen::VectorXd r_base = r0 - q_base * (q_base.transpose() * r0);
  s.rss_base = r_base.squaredNorm();
  Eigen::MatrixXd unique = all.rightCols(extra.cols()) - q_base * (q_base.transpose() * all.rightCols(extra.cols()));
  s.own = 1.0;
  for (Eigen::Index c = 0; c < unique.cols(); ++c) {
    if (unique.col(c).norm() < kNewDirection) unique.col(c).setZero();
    else s.own = std::min(s.own, unique.col(c).norm());
  }
  auto extra_qr = Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(unique, what + " (its own columns)");
  extra_qr.setThreshold(kNewDirection);
  s.extra = static_cast<int>(extra_qr.rank());
  s.rank = base_rank + s.extra;
  const Eigen::MatrixXd q_extra = Eigen::MatrixXd(extra_qr.householderQ()).leftCols(s.extra);
  s.explained = q_extra * (q_extra.transpose() * r_base);
  s.rss = std::max(0.0, s.rss_base - s.explained.squaredNorm());
  // Effect estimates: minimum-norm least squares on the whole system, then undo the column scaling.
  const auto cod = Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(all, what + " (the whole system)");
  const Eigen::VectorXd solution = cod.solve(-r0);
  const double dof = std::max(1.0, static_cast<double>(all.rows() - s.rank));
  const double sigma2 = s.rss / dof;
  const Eigen::MatrixXd normal_inverse = cod.pseudoInverse() * cod.pseudoInverse().transpose();
  s.effect.resize(extra.cols());
  s.effect_u.resize(extra.cols());
  for (Eigen::Index c = 0; c < extra.cols(); ++c) {
    const Eigen::Index k = base.cols() + c;
    const double n = norms[k] > 0 ? norms[k] : 1.0;
    s.effect[c] = solution[k] / n;
    s.effect_u[c] = std::sqrt(std::max(0.0, sigma2 * normal_inverse(k, k))) / n;
  }
  return s;
}

// ScoreColumns without the equations of some observations: centres flagged as blunders, whose 80 um would otherwise
// swamp the F-test of a 5 um effect (and pull its estimate).
LinearScore ScoreColumnsWithout(const std::vector<int>& left_out, const Eigen::VectorXd& r0, const Eigen::MatrixXd& base,
                                const Eigen::MatrixXd& extra, std::string_view candidate) {
  if (left_out.empty()) return ScoreColumns(r0, base, extra, candidate);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < r0.size(); ++i) {
    if (std::find(left_out.begin(), left_out.end(), static_cast<int>(i / 3)) == left_out.end()) rows.push_back(i);
  }
  return ScoreColumns(r0(rows), base(rows, Eigen::all), extra(rows, Eigen::all), candidate);
}

// d(residual)/d(drift rate) per coordinate: the centres move by rate * DriftShape(t).
Eigen::MatrixXd DriftColumns(const MeasurementSet& set, double tau) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()), 3);
  for (size_t i = 0; i < set.observations.size(); ++i) {
    for (int c = 0; c < 3; ++c) columns(3 * static_cast<Eigen::Index>(i) + c, c) = -DriftShape(set.t_s[i], tau);
  }
  return columns;
}

// d(residual)/d(scale): stitched xy distances from the first tile grow by scale * (s - a).
Eigen::MatrixXd ScaleColumn(const MeasurementSet& set) {
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(set.observations.size()), 1);
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const Observation& o = set.observations[i];
    const Eigen::Vector3d a = set.anchors[static_cast<size_t>(o.group)];
    columns.block<2, 1>(3 * static_cast<Eigen::Index>(i), 0) = -(o.measured - a).head<2>();
  }
  return columns;
}

}  // namespace fvm::stage
