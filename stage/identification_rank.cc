// The rank treatment of an identification (stage/identification_rank.h): the problem linearised at zero error in
// units of the plausible sizes, the columns that others (or nothing) explain exactly and the weakly determined ones
// fixed at zero with the reason, what the kept coefficients absorb of them, and where the solver starts.

#include "stage/identification_rank.h"

#include <fmt/core.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/dense_decomposition.h"
#include "stage/linear_dependence.h"
#include "stage/stitched_frame.h"

namespace fvm::stage {

const ParameterLayout::Coefficient& FreeCoefficient(const ParameterLayout& layout, int slot) {
  return layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(slot)]))];
}

namespace {

// Order in which coefficients are kept when the data cannot tell some apart: lower powers first; within a
// power, translations (positioning, straightness), then squareness, then yaw, then pitch and roll, whose effect
// needs a height change that a flat artefact hardly gives.
std::vector<int> KeepingOrder(const ParameterLayout& layout) {
  const auto rank = [&](int slot) {
    const ParameterLayout::Coefficient& c =
        layout.coefficients()[static_cast<size_t>(layout.FindCoefficient(layout.FreeNames()[static_cast<size_t>(slot)]))];
    const ErrorTerm& term = GetErrorTerm(c.term);
    int kind = 0;
    if (term.kind == ErrorKind::kSquareness) kind = 1;
    if (term.kind == ErrorKind::kRotation) kind = term.component == 2 ? 2 : 3;
    return std::make_tuple(c.power, kind, slot);
  };
  std::vector<int> order(static_cast<size_t>(layout.NumFree()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return rank(a) < rank(b); });
  return order;
}

std::string FormatValue(const ParameterLayout::Coefficient& c, double si) {
  const DisplayUnit unit = UnitOf(c);
  return fmt::format("{:.3g} {}", si * unit.per_si, unit.name);
}

// How the kept coefficients take up each fixed one on these data (linearised least squares in units of the
// plausible sizes `tau`): d(kept) / d(fixed) = N_kk^-1 N_kf from the normal equations of all columns, the pose's
// rows left out. Kept coefficient columns, in order, are the final layout's free slots.
Calibration::Undetermined Absorbed(const Eigen::MatrixXd& normal, const Eigen::MatrixXd& kept_normal,
                                   const std::vector<bool>& fixed, const Eigen::VectorXd& tau,
                                   const std::vector<std::string>& names, Eigen::Index n_coefficients) {
  std::vector<int> kept, dropped;
  for (size_t c = 0; c < fixed.size(); ++c) (fixed[c] ? dropped : kept).push_back(static_cast<int>(c));
  Calibration::Undetermined u;
  if (dropped.empty() || kept.empty() || kept_normal.rows() != static_cast<Eigen::Index>(kept.size())) return u;
  Eigen::MatrixXd cross(kept_normal.rows(), static_cast<Eigen::Index>(dropped.size()));
  for (Eigen::Index a = 0; a < cross.rows(); ++a) {
    for (Eigen::Index b = 0; b < cross.cols(); ++b) cross(a, b) = normal(kept[static_cast<size_t>(a)], dropped[static_cast<size_t>(b)]);
  }
  const Eigen::MatrixXd taken =
      Decompose<Eigen::LDLT<Eigen::MatrixXd>>(kept_normal, "the undetermined parameters: the kept normal equations").solve(cross);
  Eigen::Index free = 0;
  for (int c : kept) free += c < n_coefficients ? 1 : 0;
  u.absorbed.resize(free, cross.cols());
  for (Eigen::Index b = 0; b < cross.cols(); ++b) {
    const int d = dropped[static_cast<size_t>(b)];
    u.names.push_back(names[static_cast<size_t>(d)]);
    for (Eigen::Index a = 0; a < free; ++a) u.absorbed(a, b) = tau[kept[static_cast<size_t>(a)]] * taken(a, b) / tau[d];
  }
  return u;
}

// The problem linearised at zero error (the model is linear in its coefficients to first order), its columns in
// units of the plausible sizes `tau`: what the rank treatment works on. The pose's columns follow the coefficients'.
struct ScaledLinearisation {
  Eigen::Index n_coefficients = 0;
  Eigen::VectorXd tau, gradient;
  Eigen::MatrixXd r_factor;  // R of J = QR: the column geometry of J in n x n
  double r0_squared = 0.0;
  std::vector<std::string> names;  // the free coefficients, then the pose's
  std::vector<int> keeping_order;  // the pose first, then KeepingOrder
  std::vector<int> rank_of;        // position of each column in keeping_order
  bool IsPose(int column) const { return column >= n_coefficients; }
};

// R of J = QR, J overwritten. A tall J is cut in two row blocks, factored side by side, and their stacked R's once
// more: its R is an R of J (R^T R = J^T J, the same column geometry: [Demmel 2012]'s TSQR). The cut does not
// depend on the threads, so neither do the rounding errors.
Eigen::MatrixXd UpperFactor(Eigen::MatrixXd& j, int threads) {
  const char* what = "identification: the Jacobian of the model and the pose";
  const Eigen::Index n = j.cols(), m = j.rows();
  if (m < 4096 || m < 16 * n) {
    const auto qr = Decompose<Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>>>(Eigen::Ref<Eigen::MatrixXd>(j), what);
    return qr.matrixQR().topRows(std::min(n, m)).triangularView<Eigen::Upper>();
  }
  constexpr Eigen::Index kParts = 2;
  Eigen::MatrixXd stacked(kParts * n, n);
  const auto factor = [&](Eigen::Index part) {
    const Eigen::Index begin = part * (m / kParts), end = part + 1 == kParts ? m : begin + m / kParts;
    Eigen::Ref<Eigen::MatrixXd> rows = j.middleRows(begin, end - begin);
    const auto qr = Decompose<Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>>>(rows, what);
    stacked.middleRows(part * n, n) = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  };
  if (threads == 1) {
    for (Eigen::Index part = 0; part < kParts; ++part) factor(part);
  } else {
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] { tbb::parallel_for(Eigen::Index{0}, kParts, factor); });
  }
  const auto qr = Decompose<Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>>>(Eigen::Ref<Eigen::MatrixXd>(stacked), what);
  return qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
}

ScaledLinearisation LineariseScaled(const ParameterLayout& layout, const Prepared& prepared, int pose_count) {
  const std::vector<double> zeros(static_cast<size_t>(layout.NumFree()), 0.0);
  Eigen::VectorXd r0;
  Eigen::MatrixXd j;
  Linearise(layout, zeros, prepared.pose6.data(), prepared, &r0, &j);
  // Polynomial bases are defined on their travel; far outside it (or on a travel of 1e-300 mm) their powers
  // overflow, and a rank search on inf and NaN reads memory it does not own (Eigen's pivoting).
  if (!j.allFinite() || !r0.allFinite()) {
    throw std::invalid_argument("the model cannot be evaluated at these points (its derivatives overflow): do the "
                                "points lie inside the travel the error functions are defined on?");
  }
  ScaledLinearisation s;
  s.n_coefficients = layout.NumFree();
  s.tau.resize(s.n_coefficients + pose_count);
  s.tau << PlausibleSizes(layout), prepared.pose_scale.head(pose_count);
  j.array().rowwise() *= s.tau.transpose().array();  // columns in units of the plausible sizes
  s.gradient = j.transpose() * r0;
  s.r0_squared = r0.squaredNorm();
  // Dependences are searched and normal equations formed on R. (In place: j is large, 3 rows per point.)
  s.r_factor = UpperFactor(j, prepared.threads);
  s.names = layout.FreeNames();
  for (int i = 0; i < pose_count; ++i) s.names.push_back(PoseParameterNames()[static_cast<size_t>(i)]);
  // The pose comes first: it is never fixed, and coefficients that only move the whole point set (constant
  // terms next to the tracker) are named as aliases of it.
  for (int i = 0; i < pose_count; ++i) s.keeping_order.push_back(static_cast<int>(s.n_coefficients) + i);
  for (int c : KeepingOrder(layout)) s.keeping_order.push_back(c);
  s.rank_of.resize(s.names.size());
  for (size_t i = 0; i < s.keeping_order.size(); ++i) s.rank_of[static_cast<size_t>(s.keeping_order[i])] = static_cast<int>(i);
  return s;
}

// Why a column without an effect of its own on these data is fixed.
std::string NoEffectReason(const std::vector<Observation>& observations, const IdentificationOptions& options) {
  const bool displacements = std::all_of(observations.begin(), observations.end(), [](const Observation& o) { return o.from.has_value(); });
  return displacements ? "no effect on these data: displacements between tiles, seen from the first tile, show no constant offset or turn"
         : options.anchor != Anchor::kFirstTile ? "no effect on these data"
         : options.frame == StitchedFrame::kRotated
             ? "no effect on these data: every measurement is seen from its own first tile, offset and turned "
               "with the stage there, which cancels it"
             : "no effect on these data: anchoring every measurement at its first tile cancels it";
}

// Fixes the columns the others (or nothing) explain exactly, naming what takes their place; a dependent pose
// column is an error.
void FixDependentColumns(const ScaledLinearisation& s, const std::vector<Observation>& observations,
                         const IdentificationOptions& options, std::vector<bool>& fixed, std::vector<FixedCoefficient>& named) {
  for (const ColumnDependence& d : FindDependentColumns(s.r_factor, s.keeping_order, options.alias_tolerance)) {
    if (s.IsPose(d.column)) {
      throw std::invalid_argument(fmt::format(
          "the points do not determine the instrument pose ({} has no effect of its own): measure points that span "
          "the workspace in all three axes, or hold the pose", s.names[static_cast<size_t>(d.column)]));
    }
    fixed[static_cast<size_t>(d.column)] = true;
    std::string why;
    if (d.on.empty()) {
      why = NoEffectReason(observations, options);
    } else {
      why = "same effect as";
      for (size_t k = 0; k < d.on.size(); ++k) {
        const auto [other, factor] = d.on[k];
        why += fmt::format("{} {:.4g} * {}", k ? " +" : "", factor * s.tau[other] / s.tau[d.column],
                           s.names[static_cast<size_t>(other)]);
      }
      why += " on these data";
      if (std::any_of(d.on.begin(), d.on.end(), [&](const auto& o) { return s.IsPose(o.first); })) {
        why += " (the instrument pose absorbs it: error functions are only known up to their value at the origin)";
      }
    }
    named.push_back({s.names[static_cast<size_t>(d.column)], why});
  }
}

// The kept column the weakly determined `worst` is most correlated with.
Eigen::Index MostCorrelated(const Eigen::MatrixXd& covariance, Eigen::Index worst) {
  Eigen::Index partner = worst == 0 ? 1 : 0;
  for (Eigen::Index a = 0; a < covariance.rows(); ++a) {
    if (a == worst) continue;
    const double rho = std::abs(covariance(worst, a)) / std::sqrt(covariance(a, a) * covariance(worst, worst));
    const double best = std::abs(covariance(worst, partner)) / std::sqrt(covariance(partner, partner) * covariance(worst, worst));
    if (rho > best) partner = a;
  }
  return partner;
}

std::string UndeterminedReason(const ParameterLayout& layout, const ScaledLinearisation& s, const std::vector<int>& kept,
                               const Eigen::MatrixXd& covariance, Eigen::Index worst) {
  const double u = std::sqrt(std::max(0.0, covariance(worst, worst)));
  const int column = kept[static_cast<size_t>(worst)];
  const Eigen::Index partner = MostCorrelated(covariance, worst);
  const ParameterLayout::Coefficient& c = FreeCoefficient(layout, column);
  std::string why = fmt::format(
      "undetermined by these data: its standard uncertainty would be {}, {:.0f}% of a plausible {}", FormatValue(c, u * s.tau[column]),
      100.0 * u, FormatValue(c, s.tau[column]));
  if (kept.size() > 1) {
    const double rho = covariance(worst, partner) / std::sqrt(covariance(partner, partner) * covariance(worst, worst));
    why += fmt::format(" (correlation {:+.3f} with {})", rho, s.names[static_cast<size_t>(kept[static_cast<size_t>(partner)])]);
  }
  const ErrorTerm& term = GetErrorTerm(c.term);
  if (term.kind == ErrorKind::kRotation && term.component != 2) why += "; pitch and roll need height changes";
  return why;
}

// Weakly determined coefficients: fixes the worst while one's standard uncertainty, in units of its plausible
// size, exceeds the limit. Normal equations on scaled columns are well enough conditioned here.
KeptStart FixWeaklyDetermined(const ParameterLayout& layout, const ScaledLinearisation& s, const Eigen::MatrixXd& normal,
                              int equations, bool weighted, const IdentificationOptions& options, std::vector<bool>& fixed,
                              std::vector<FixedCoefficient>& named) {
  KeptStart start;
  while (true) {
    std::vector<int> kept;
    for (size_t c = 0; c < fixed.size(); ++c) {
      if (!fixed[c]) kept.push_back(static_cast<int>(c));
    }
    const Eigen::Index k = static_cast<Eigen::Index>(kept.size());
    if (k == 0) break;
    Eigen::MatrixXd nk(k, k);
    Eigen::VectorXd gk(k);
    for (Eigen::Index a = 0; a < k; ++a) {
      gk[a] = s.gradient[kept[static_cast<size_t>(a)]];
      for (Eigen::Index b = 0; b < k; ++b) nk(a, b) = normal(kept[static_cast<size_t>(a)], kept[static_cast<size_t>(b)]);
    }
    const auto ldlt = Decompose<Eigen::LDLT<Eigen::MatrixXd>>(nk, "identification: the normal equations of the kept parameters");
    const Eigen::VectorXd solution = -ldlt.solve(gk);
    const double rss = std::max(0.0, s.r0_squared - gk.dot(ldlt.solve(gk)));
    const double dof = std::max(1.0, static_cast<double>(equations - k));
    const double sigma = VarianceFactor(weighted, options.noise_floor_mm, rss, dof);
    const Eigen::MatrixXd covariance = sigma * sigma * ldlt.solve(Eigen::MatrixXd::Identity(k, k));
    // Of the coefficients the data cannot determine, fix the one we would keep last (KeepingOrder): when
    // pitch and a squareness term explain the same thing, the squareness stays. The pose is never fixed.
    Eigen::Index worst = -1;
    for (Eigen::Index a = 0; a < k; ++a) {
      if (s.IsPose(kept[static_cast<size_t>(a)])) continue;
      const double u = std::sqrt(std::max(0.0, covariance(a, a)));
      if (!(u <= options.max_relative_uncertainty)) {
        if (worst < 0 || s.rank_of[static_cast<size_t>(kept[static_cast<size_t>(a)])] >
                             s.rank_of[static_cast<size_t>(kept[static_cast<size_t>(worst)])]) {
          worst = a;
        }
      }
    }
    if (worst < 0) {
      start.parameters.assign(solution.data(), solution.data() + solution.size());
      start.normal = nk;
      break;
    }
    const int column = kept[static_cast<size_t>(worst)];
    named.push_back({s.names[static_cast<size_t>(column)], UndeterminedReason(layout, s, kept, covariance, worst)});
    fixed[static_cast<size_t>(column)] = true;
  }
  return start;
}
}  // namespace

// The rank treatment: what these data cannot determine is fixed at zero (result->fixed, and what the kept
// coefficients absorb of it); returns where the solver starts.
KeptStart TreatRank(const ParameterLayout& layout, const std::vector<Observation>& observations, const Prepared& prepared,
                    const IdentificationOptions& options, int equations, int pose_count, IdentificationResult& result) {
  const ScaledLinearisation s = LineariseScaled(layout, prepared, pose_count);
  std::vector<bool> fixed(s.names.size(), false);
  FixDependentColumns(s, observations, options, fixed, result.fixed);
  const Eigen::MatrixXd normal = s.r_factor.transpose() * s.r_factor;
  KeptStart start = FixWeaklyDetermined(layout, s, normal, equations, prepared.weighted, options, fixed, result.fixed);
  result.calibration.undetermined = Absorbed(normal, start.normal, fixed, s.tau, s.names, s.n_coefficients);
  return start;
}

}  // namespace fvm::stage
