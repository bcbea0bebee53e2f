#include "imaging/field_distortion_fit.h"
#include "core/dense_decomposition.h"
#include "core/statistics.h"
#include "imaging/registration_floor.h"

#include <ceres/ceres.h>
#include <fmt/core.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <set>

namespace fvm::imaging {

void FieldDistortionFitOptions::Check() const {
  FieldDistortionTermNames(order);  // throws outside 2..kMaxDistortionOrder
  if (!(max_field_sigma_px > 0.0) || min_pair_points < 3 || !(huber_sigmas > 0.0) || threads < 1) {
    throw std::invalid_argument(
        "field distortion fit: max field sigma > 0, at least 3 points a pair, Huber > 0, 1 thread or more");
  }
}

namespace {

// One correspondence: r = p_a - p_b + (u_a - u_b) + (B(u_a) - B(u_b)) c, scaled by 1 / sigma. Linear: its
// Jacobian is a constant.
class OverlapPointCost : public ceres::CostFunction {
 public:
  OverlapPointCost(const Eigen::Vector2d& delta_u, const Eigen::Matrix<double, 2, Eigen::Dynamic>& g, double sigma)
      : delta_u_(delta_u), g_(g), weight_(1.0 / sigma) {
    set_num_residuals(2);
    mutable_parameter_block_sizes()->assign({2, 2, static_cast<int>(g.cols())});
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector2d> pa(parameters[0]), pb(parameters[1]);
    const Eigen::Map<const Eigen::VectorXd> c(parameters[2], g_.cols());
    Eigen::Map<Eigen::Vector2d> r(residuals);
    r = weight_ * (pa - pb + delta_u_ + g_ * c);
    if (jacobians) {
      for (int k = 0; k < 2; ++k) {
        if (!jacobians[k]) continue;
        Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> j(jacobians[k]);
        j = (k == 0 ? weight_ : -weight_) * Eigen::Matrix2d::Identity();
      }
      if (jacobians[2]) {
        Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor>> j(jacobians[2], 2, g_.cols());
        j = weight_ * g_;
      }
    }
    return true;
  }

 private:
  Eigen::Vector2d delta_u_;
  Eigen::Matrix<double, 2, Eigen::Dynamic> g_;
  double weight_;
};

struct FitPoint {
  int pair, a, b;
  Eigen::Vector2d delta_u;
  Eigen::Matrix<double, 2, Eigen::Dynamic> g;
};

std::string JoinTerms(const std::vector<std::string>& names, const std::vector<int>& which) {
  std::vector<std::string> out;
  for (int k : which) out.push_back(names[static_cast<size_t>(k)]);
  return fmt::format("{}", fmt::join(out, ", "));
}

// An overlap's correspondences kept for the block scatter: where each lies in tile a and what the fit left of it,
// and the direction of the step between the two tiles (the band runs across it).
struct BandPoint {
  Eigen::Vector2d a_px, residual;
};
struct OverlapBand {
  bool step_along_x = true;
  std::vector<BandPoint> points;
};

// How much more the correspondences' errors scatter at the scale of a quarter of an overlap than their own scatter
// allows: each pair's inliers split into four blocks along its band (across the step) by their place in tile a,
// each block's mean residual about the pair's (which the positions take up) against sigma^2 / n. The points of one
// overlap share errors at the matching windows' scale and beyond (the texture's, the resampling's) that move the
// field's terms; no loop of a grid checks them, and a chain of tiles has no loop at all: on scangen's scans
// (512 px, 20 %) the quarters scatter 1.4-1.6 times the points' sigma, and the field's coefficients missed their
// truth by 1.5-1.9 times their unwidened u; on a rendered 3 x 3 grid 2.1 times (there halves of the band scatter
// no more, blocks across the band less: 0.7-0.9). At least 1.
// `dof` receives the blocks' degrees of freedom (2 x 3 a pair).
double OverlapBlockScatter(const std::vector<OverlapBand>& bands, double sigma, int& dof) {
  constexpr int kBlocks = 4;
  double chi2 = 0.0;
  dof = 0;
  for (const OverlapBand& band : bands) {
    std::vector<BandPoint> pair = band.points;
    const int n = static_cast<int>(pair.size());
    if (n < 2 * kBlocks) continue;
    const int axis = band.step_along_x ? 1 : 0;  // along the band
    std::sort(pair.begin(), pair.end(), [axis](const BandPoint& l, const BandPoint& r) { return l.a_px(axis) < r.a_px(axis); });
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const BandPoint& p : pair) mean += p.residual;
    mean /= n;
    for (int b = 0; b < kBlocks; ++b) {
      const int first = b * n / kBlocks, end = (b + 1) * n / kBlocks;
      Eigen::Vector2d block = Eigen::Vector2d::Zero();
      for (int m = first; m < end; ++m) block += pair[static_cast<size_t>(m)].residual;
      block /= end - first;
      chi2 += (block - mean).squaredNorm() * (end - first) / (sigma * sigma);
    }
    dof += 2 * (kBlocks - 1);
  }
  return dof > 0 && sigma > 0.0 ? std::max(1.0, std::sqrt(chi2 / dof)) : 1.0;
}

// What a shift shared by every point of one overlap does to the solution: the floor of a registered pair
// (kRegistrationFloorPx, what resampling and shading leave of any shift) applied to each overlap as a whole, as the
// rigid registration applies it to each pair. In a chain the positions take it up entirely; through a grid's loops
// it reaches the other tiles and the field. The linearised solution moves by C G_q e for a shift e of pair q, C the
// unscaled covariance, G_q = sum over its points of w J^T dr/de (w the robust weight over the weighting sigma^2,
// dr/de the identity: e enters like tile a's position): sum_q f^2 C G_q G_q^T C, one product for all pairs.
template <typename Residual>
Eigen::MatrixXd PairFloorCovariance(const std::vector<FitPoint>& points, const Residual& residual_of,
                                    const Eigen::MatrixXd& covariance, const std::vector<int>& column, int free_params,
                                    int field_terms, size_t pairs, double weighted_sigma, double huber_sigmas) {
  // G_q in three parts: its rows at tile a's position, at tile b's (the negative) and at the field's terms.
  struct PairPull {
    int a = -1, b = -1;
    double weight = 0.0;
    Eigen::MatrixXd field;
  };
  std::vector<PairPull> pulls(pairs, PairPull{-1, -1, 0.0, Eigen::MatrixXd::Zero(field_terms, 2)});
  for (const FitPoint& p : points) {
    const double s = (residual_of(p) / weighted_sigma).squaredNorm();
    const double w = (s <= huber_sigmas * huber_sigmas ? 1.0 : huber_sigmas / std::sqrt(s)) / (weighted_sigma * weighted_sigma);
    PairPull& pull = pulls[static_cast<size_t>(p.pair)];
    pull.a = column[static_cast<size_t>(p.a)], pull.b = column[static_cast<size_t>(p.b)];
    pull.weight += w;
    if (field_terms > 0) pull.field += w * p.g.transpose();
  }
  const Eigen::Index n = covariance.rows();
  Eigen::MatrixXd moved = Eigen::MatrixXd::Zero(n, 2 * static_cast<Eigen::Index>(pairs));
  for (size_t q = 0; q < pairs; ++q) {
    auto m = moved.middleCols(2 * static_cast<Eigen::Index>(q), 2);
    const PairPull& pull = pulls[q];
    if (pull.a >= 0) m += pull.weight * covariance.middleCols(pull.a, 2);
    if (pull.b >= 0) m -= pull.weight * covariance.middleCols(pull.b, 2);
    if (field_terms > 0) m += covariance.middleCols(free_params, field_terms) * pull.field;
  }
  return kRegistrationFloorPx * kRegistrationFloorPx * moved * moved.transpose();
}

// The coefficients' information once the positions are solved for (the Schur complement of the unit-weight normal
// equations): a direction with none is a combination of terms no overlap sees. Throws naming them.
void RefuseUnseenTerms(const std::vector<FitPoint>& points, const std::vector<int>& column, int free_params, int k,
                       const std::vector<std::string>& names) {
  // J^T J block by block: a point's Jacobian is +I at a's position, -I at b's and g at the coefficients.
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(free_params + k, free_params + k);
  for (const FitPoint& p : points) {
    const int ca = column[static_cast<size_t>(p.a)], cb = column[static_cast<size_t>(p.b)];
    const std::array<std::pair<int, double>, 2> sides = {std::pair{ca, 1.0}, std::pair{cb, -1.0}};
    for (const auto& [ci, si] : sides) {
      if (ci < 0) continue;
      for (const auto& [cj, sj] : sides) {
        if (cj >= 0) n.block<2, 2>(ci, cj) += si * sj * Eigen::Matrix2d::Identity();
      }
      n.block(ci, free_params, 2, k) += si * p.g;
      n.block(free_params, ci, k, 2) += si * p.g.transpose();
    }
    n.bottomRightCorner(k, k).noalias() += p.g.transpose() * p.g;
  }
  Eigen::MatrixXd s = n.bottomRightCorner(k, k);
  if (free_params > 0) {
    const auto pp = Decompose<Eigen::LDLT<Eigen::MatrixXd>>(Eigen::MatrixXd(n.topLeftCorner(free_params, free_params)),
                                                            "the field fit: the positions' information");
    s -= n.bottomLeftCorner(k, free_params) * pp.solve(n.topRightCorner(free_params, k));
  }
  Eigen::VectorXd scale = n.bottomRightCorner(k, k).diagonal().cwiseSqrt();
  std::vector<int> unseen;
  for (int t = 0; t < k; ++t) {
    if (!(scale(t) > 0.0)) unseen.push_back(t), scale(t) = 1.0;
  }
  if (unseen.empty()) {
    const Eigen::MatrixXd normalised = scale.cwiseInverse().asDiagonal() * s * scale.cwiseInverse().asDiagonal();
    const auto eigen = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>>(
        normalised, "the field fit: the terms' information less the positions'");
    // The projector onto the directions without information: a term whose own direction lies a tenth or more in
    // it is named (whatever basis of those directions the solver returns).
    Eigen::MatrixXd projector = Eigen::MatrixXd::Zero(k, k);
    for (int e = 0; e < k; ++e) {
      if (eigen.eigenvalues()(e) > 1e-7 * eigen.eigenvalues().maxCoeff()) continue;
      projector += eigen.eigenvectors().col(e) * eigen.eigenvectors().col(e).transpose();
    }
    for (int t = 0; t < k; ++t) {
      if (projector(t, t) > 0.1) unseen.push_back(t);
    }
  }
  if (!unseen.empty()) {
    throw FieldDistortionUndeterminable(fmt::format(
        "the overlaps cannot determine the field distortion's terms {}: an overlap sees only how the field changes "
        "along the step between its two tiles, so a strip of tiles in one direction never sees terms in the other "
        "coordinate alone; register a grid (or scans) with steps along both x and y, or lower the order",
        JoinTerms(names, unseen)));
  }
}

// Overlaps that all step along x (or all along y) see how the field changes along that axis only: nothing of
// what depends on the other coordinate alone. Named as fields, since the basis spans them through several terms.
void RefuseOneDirection(const std::vector<const PairCorrespondences*>& used, int order) {
  int along_x = 0, along_y = 0;
  for (const PairCorrespondences* p : used) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (size_t m = 0; m < p->a_px.size(); ++m) mean += p->a_px[m] - p->b_px[m];
    (std::abs(mean.x()) >= std::abs(mean.y()) ? along_x : along_y) += 1;
  }
  if (along_x > 0 && along_y > 0) return;
  const char* other = along_x > 0 ? "y" : "x";
  std::vector<std::string> fields;
  for (int j = 2; j <= order; ++j) {
    for (const char* component : {"dx", "dy"}) fields.push_back(fmt::format("{}_{}{}", component, other, j));
  }
  throw FieldDistortionUndeterminable(fmt::format(
      "the overlaps cannot determine the field distortion's terms in {} alone ({}): all {} overlaps step along {}, "
      "and an overlap sees only how the field changes along its step; register a grid (or scans) with steps "
      "along both x and y",
      other, fmt::join(fields, ", "), used.size(), along_x > 0 ? "x" : "y"));
}

}  // namespace

FieldDistortionFit FitFieldDistortion(const std::vector<PairCorrespondences>& pairs,
                                      const std::vector<Eigen::Vector2d>& initial_px, const std::vector<bool>& fixed,
                                      int width_px, int height_px, const FieldDistortionFitOptions& options,
                                      const FieldDistortion* known) {
  options.Check();
  if (known && (known->Identity() || known->width_px != width_px || known->height_px != height_px)) {
    throw std::invalid_argument(fmt::format("FitFieldDistortion: the known field is for {} x {} px tiles, these are "
                                            "{} x {}", known->width_px, known->height_px, width_px, height_px));
  }
  if (fixed.size() != initial_px.size()) throw std::invalid_argument("FitFieldDistortion: one fixed flag per tile");
  const int tiles = static_cast<int>(initial_px.size());
  FieldDistortionFit fit;
  fit.field.width_px = width_px, fit.field.height_px = height_px;
  fit.field.order = known ? known->order : options.order;
  const std::vector<std::string>& names = FieldDistortionTermNames(fit.field.order);
  const int k = static_cast<int>(names.size());
  fit.field.coefficients = known ? known->coefficients : Eigen::VectorXd::Zero(k);

  // The usable pairs; every connected group of tiles keeps one position fixed (its lowest index, unless given).
  std::vector<int> group(static_cast<size_t>(tiles));
  std::iota(group.begin(), group.end(), 0);
  const auto root = [&](int i) {
    while (group[static_cast<size_t>(i)] != i) i = group[static_cast<size_t>(i)] = group[static_cast<size_t>(group[static_cast<size_t>(i)])];
    return i;
  };
  std::vector<const PairCorrespondences*> used;
  std::vector<bool> reached(static_cast<size_t>(tiles), false);
  for (const PairCorrespondences& p : pairs) {
    if (p.a < 0 || p.b < 0 || p.a >= tiles || p.b >= tiles || p.a == p.b || p.a_px.size() != p.b_px.size()) {
      throw std::invalid_argument("FitFieldDistortion: a pair's tiles or points do not match");
    }
    if (static_cast<int>(p.a_px.size()) < options.min_pair_points) {
      ++fit.pairs_without_texture;
      continue;
    }
    used.push_back(&p);
    reached[static_cast<size_t>(p.a)] = reached[static_cast<size_t>(p.b)] = true;
    const int ra = root(p.a), rb = root(p.b);
    if (ra != rb) group[static_cast<size_t>(std::max(ra, rb))] = std::min(ra, rb);
  }
  if (used.empty()) {
    throw FieldDistortionUndeterminable(fmt::format(
        "no overlap has texture the field distortion can be followed in ({} pairs, none with {} or more tracked "
        "points): a texture-free overlap shows no distortion; image a textured part",
        pairs.size(), options.min_pair_points));
  }
  std::vector<bool> hold = fixed;
  std::set<int> anchored;
  for (int i = 0; i < tiles; ++i) {
    if (!reached[static_cast<size_t>(i)]) hold[static_cast<size_t>(i)] = true;
    if (hold[static_cast<size_t>(i)]) anchored.insert(root(i));
  }
  for (int i = 0; i < tiles; ++i) {
    if (!anchored.count(root(i))) hold[static_cast<size_t>(i)] = true, anchored.insert(root(i));
  }
  std::vector<int> column(static_cast<size_t>(tiles), -1);
  int free_params = 0;
  for (int i = 0; i < tiles; ++i) {
    if (!hold[static_cast<size_t>(i)]) column[static_cast<size_t>(i)] = free_params, free_params += 2;
  }

  // The terms solved for (all but the held ones): each point's g has their columns only.
  if (!known && options.hold_stretch_terms) {
    fit.held_terms = FieldDistortionStretchTerms(fit.field.order), fit.held_reason = kHeldStretchTerms;
  }
  if (!known && !options.hold_terms.empty()) {
    for (int t : options.hold_terms) {
      if (t < 0 || t >= k) throw std::invalid_argument("FitFieldDistortion: a held term outside the order's terms");
      if (std::find(fit.held_terms.begin(), fit.held_terms.end(), t) == fit.held_terms.end()) fit.held_terms.push_back(t);
    }
    std::sort(fit.held_terms.begin(), fit.held_terms.end());
    fit.held_reason = fit.held_reason.empty() ? options.hold_reason : fit.held_reason + "; " + options.hold_reason;
  }
  std::vector<int> solved;
  for (int t = 0; t < k; ++t) {
    if (std::find(fit.held_terms.begin(), fit.held_terms.end(), t) == fit.held_terms.end()) solved.push_back(t);
  }
  const int ks = static_cast<int>(solved.size());
  std::vector<std::string> solved_names;
  for (int t : solved) solved_names.push_back(names[static_cast<size_t>(t)]);
  std::vector<FitPoint> points;
  for (size_t q = 0; q < used.size(); ++q) {
    const PairCorrespondences& p = *used[q];
    for (size_t m = 0; m < p.a_px.size(); ++m) {
      const Eigen::Matrix<double, 2, Eigen::Dynamic> g = fit.field.Basis(p.a_px[m], p.kernel) - fit.field.Basis(p.b_px[m], p.kernel);
      Eigen::Matrix<double, 2, Eigen::Dynamic> gs(2, ks);
      for (int s = 0; s < ks; ++s) gs.col(s) = g.col(solved[static_cast<size_t>(s)]);
      points.push_back({static_cast<int>(q), p.a, p.b, p.a_px[m] - p.b_px[m], std::move(gs)});
    }
  }
  fit.points = static_cast<int>(points.size());
  fit.pairs_used = static_cast<int>(used.size());
  if (!known) {
    RefuseOneDirection(used, options.order);
    RefuseUnseenTerms(points, column, free_params, ks, solved_names);
  }

  std::vector<std::array<double, 2>> position(static_cast<size_t>(tiles));
  for (int i = 0; i < tiles; ++i) position[static_cast<size_t>(i)] = {initial_px[static_cast<size_t>(i)].x(), initial_px[static_cast<size_t>(i)].y()};
  Eigen::VectorXd c(ks);  // the solved terms' coefficients
  for (int s = 0; s < ks; ++s) c(s) = fit.field.coefficients(solved[static_cast<size_t>(s)]);
  const auto residual_of = [&](const FitPoint& p) {
    const Eigen::Map<const Eigen::Vector2d> pa(position[static_cast<size_t>(p.a)].data()), pb(position[static_cast<size_t>(p.b)].data());
    return Eigen::Vector2d(pa - pb + p.delta_u + p.g * c);
  };
  const auto robust_sigma = [&] {
    std::vector<double> abs;
    for (const FitPoint& p : points) {
      const Eigen::Vector2d r = residual_of(p);
      abs.push_back(std::abs(r.x())), abs.push_back(std::abs(r.y()));
    }
    // No point, no scatter: the floor (HighMedian would give NaN, which std::max passes on).
    return abs.empty() ? 1e-3 : std::max(1.4826 * HighMedian(std::move(abs)), 1e-3);
  };
  {
    double sum = 0.0;
    for (const FitPoint& p : points) sum += (residual_of(p) - p.g * c).squaredNorm();  // d = 0
    fit.rigid_rms_px = std::sqrt(sum / (2.0 * points.size()));
  }

  // Solve, re-estimate the scatter of one correspondence, solve again with it: the loss bends at huber_sigmas of
  // that scatter, and the covariance below is in its units.
  double sigma = std::max(robust_sigma(), 0.05);
  double weighted_sigma = sigma;  // what the last problem's residuals were scaled by
  std::vector<double*> blocks;
  for (int i = 0; i < tiles; ++i) {
    if (!hold[static_cast<size_t>(i)]) blocks.push_back(position[static_cast<size_t>(i)].data());
  }
  if (!known) blocks.push_back(c.data());
  std::unique_ptr<ceres::Problem> problem;
  for (int pass = 0; pass < 3; ++pass) {
    problem = std::make_unique<ceres::Problem>();
    for (const FitPoint& p : points) {
      problem->AddResidualBlock(new OverlapPointCost(p.delta_u, p.g, sigma), new ceres::HuberLoss(options.huber_sigmas),
                                position[static_cast<size_t>(p.a)].data(), position[static_cast<size_t>(p.b)].data(),
                                c.data());
    }
    for (int i = 0; i < tiles; ++i) {
      if (hold[static_cast<size_t>(i)] && problem->HasParameterBlock(position[static_cast<size_t>(i)].data())) {
        problem->SetParameterBlockConstant(position[static_cast<size_t>(i)].data());
      }
    }
    if (known) problem->SetParameterBlockConstant(c.data());
    ceres::Solver::Options solver;
    // The normal equations: a few dozen unknowns against tens of thousands of residuals, where QR of the whole
    // Jacobian cost most of the solve.
    solver.linear_solver_type = free_params + ks > 300 ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::DENSE_NORMAL_CHOLESKY;
    solver.max_num_iterations = 50;
    solver.function_tolerance = 1e-12;
    solver.num_threads = options.threads;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, problem.get(), &summary);
    fit.iterations += static_cast<int>(summary.iterations.size());
    fit.solver_report = summary.BriefReport();
    if (summary.termination_type == ceres::FAILURE) {
      throw std::runtime_error("field distortion: the solve failed: " + summary.message);
    }
    weighted_sigma = sigma;
    sigma = robust_sigma();
  }
  fit.point_sigma_px = sigma;

  // The information of the last problem (its robust weights, residuals in units of its sigma), the sigma it was
  // weighted with replaced by the one its solution shows.
  if (blocks.empty()) throw std::invalid_argument("FitFieldDistortion: no position to solve");
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  ceres::CRSMatrix crs;
  problem->Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
  Eigen::SparseMatrix<double, Eigen::RowMajor> j(crs.num_rows, crs.num_cols);
  std::vector<Eigen::Triplet<double>> entries;
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int e = crs.rows[static_cast<size_t>(r)]; e < crs.rows[static_cast<size_t>(r) + 1]; ++e) {
      entries.emplace_back(r, crs.cols[static_cast<size_t>(e)], crs.values[static_cast<size_t>(e)]);
    }
  }
  j.setFromTriplets(entries.begin(), entries.end());
  const Eigen::MatrixXd information = Eigen::MatrixXd(Eigen::SparseMatrix<double>(j.transpose() * j));
  Eigen::MatrixXd covariance =
      Decompose<Eigen::LDLT<Eigen::MatrixXd>>(information, "the field fit: the information of positions and field")
          .solve(Eigen::MatrixXd::Identity(information.rows(), information.cols()));

  // Inliers' residuals; each pair's mean residual against the scatter its points allow. Positions take up two
  // components of each pair's mean, so only the loops of a grid check them. The blocks of each pair's band, which
  // no loop checks: OverlapBlockScatter.
  double inlier_sum = 0.0;
  int inliers = 0;
  std::vector<Eigen::Vector2d> pair_sum(used.size(), Eigen::Vector2d::Zero());
  std::vector<int> pair_n(used.size(), 0);
  std::vector<OverlapBand> bands(used.size());
  for (size_t q = 0; q < used.size(); ++q) {
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    for (size_t m = 0; m < used[q]->a_px.size(); ++m) step += used[q]->a_px[m] - used[q]->b_px[m];
    bands[q].step_along_x = std::abs(step.x()) >= std::abs(step.y());
  }
  {
    std::vector<size_t> next(used.size(), 0);  // each pair's points in turn, as `points` holds them
    for (const FitPoint& p : points) {
      const size_t q = static_cast<size_t>(p.pair);
      const Eigen::Vector2d& a_px = used[q]->a_px[next[q]++];
      const Eigen::Vector2d r = residual_of(p);
      if (r.cwiseAbs().maxCoeff() > 3.0 * sigma) continue;
      inlier_sum += r.squaredNorm(), ++inliers;
      pair_sum[q] += r, ++pair_n[q];
      bands[q].points.push_back({a_px, r});
    }
  }
  fit.residual_rms_px = inliers > 0 ? std::sqrt(inlier_sum / (2.0 * inliers)) : 0.0;
  double chi2 = 0.0;
  for (size_t q = 0; q < used.size(); ++q) {
    if (pair_n[q] > 0) chi2 += pair_sum[q].squaredNorm() / pair_n[q] / (sigma * sigma);
  }
  const int dof = 2 * static_cast<int>(used.size()) - free_params;
  if (dof > 0) fit.pair_scatter_factor = std::max(1.0, std::sqrt(chi2 / dof));
  fit.block_scatter_factor = OverlapBlockScatter(bands, sigma, fit.block_dof);
  const double widened = std::max(fit.pair_scatter_factor, fit.block_scatter_factor);
  covariance = widened * widened * covariance + PairFloorCovariance(points, residual_of, covariance, column, free_params,
                                                                     known ? 0 : ks, used.size(), weighted_sigma,
                                                                     options.huber_sigmas);

  for (int i = 0; i < tiles; ++i) {
    fit.positions_px.emplace_back(position[static_cast<size_t>(i)][0], position[static_cast<size_t>(i)][1]);
    const int col = column[static_cast<size_t>(i)];
    fit.position_covariance_px2.push_back(col >= 0 ? Eigen::Matrix2d(covariance.block<2, 2>(col, col))
                                                   : Eigen::Matrix2d::Zero());
  }
  if (known) {
    fit.field = *known;
    return fit;
  }
  fit.field.covariance = Eigen::MatrixXd::Zero(k, k);
  for (int s = 0; s < ks; ++s) {
    fit.field.coefficients(solved[static_cast<size_t>(s)]) = c(s);
    for (int r = 0; r < ks; ++r) {
      fit.field.covariance(solved[static_cast<size_t>(s)], solved[static_cast<size_t>(r)]) =
          covariance(free_params + s, free_params + r);
    }
  }

  // Too high an order: terms the thin overlaps pin, but not to within max_field_sigma_px over the whole tile, from
  // the correspondences' own scatter (what the overlaps' geometry and texture allow; the pairs' misfit, which a
  // better model would take up, is left out of this test).
  FieldDistortion determined = fit.field;
  determined.covariance /= widened * widened;
  std::vector<int> loose;
  for (int t : solved) {
    FieldDistortion alone = determined;
    alone.covariance = Eigen::MatrixXd::Zero(k, k);
    alone.covariance(t, t) = determined.covariance(t, t);
    if (alone.DisplacementSigmaPx() > options.max_field_sigma_px) loose.push_back(t);
  }
  if (!loose.empty() || determined.DisplacementSigmaPx() > options.max_field_sigma_px) {
    throw FieldDistortionUndeterminable(fmt::format(
        "order {} is more than these overlaps can determine: the field's standard uncertainty over the tile is "
        "{:.3f} px (limit {:.3f} px){}; the overlaps see only a thin band of each tile, and terms of high order "
        "swing freely inside it; lower the order (e.g. {})",
        options.order, determined.DisplacementSigmaPx(), options.max_field_sigma_px,
        loose.empty() ? std::string() : ", " + JoinTerms(names, loose) + " each beyond the limit alone",
        std::max(2, options.order - 1)));
  }
  return fit;
}

}  // namespace fvm::imaging
