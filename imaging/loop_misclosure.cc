#include "imaging/loop_misclosure.h"

#include "core/dense_decomposition.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace fvm::imaging {
namespace {

// One pair seen from the rest of the grid.
struct PairTest {
  Eigen::Vector2d predicted = Eigen::Vector2d::Zero();   // p_b - p_a from the other pairs and the stage
  Eigen::Matrix2d prediction_covariance = Eigen::Matrix2d::Zero();
  Eigen::Vector2d misclosure = Eigen::Vector2d::Zero();  // offset - predicted
  double statistic = 0.0;     // misclosure' (C + D)^-1 misclosure: the chi-square the pair adds
  double misclosure_px = 0.0;  // its length along the directions the pair determines
  double redundancy = 0.0;    // the pair's share of the degrees of freedom
  double chi_square = 0.0;    // its residual in the solve with every pair, r' W r
};

// The directions a pair's information determines (its eigenvectors with a non-negligible eigenvalue), as a
// projector.
Eigen::Matrix2d DeterminedDirections(const Eigen::Matrix2d& information) {
  const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(information, "a pair's information");
  Eigen::Matrix2d p = Eigen::Matrix2d::Zero();
  for (int k = 0; k < 2; ++k) {
    if (eig.eigenvalues()(k) > 1e-9 * std::max(eig.eigenvalues()(1), 1e-300)) {
      p += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
    }
  }
  return p;
}

// The least squares of the accepted pairs and the stage prior on every tile (no tile held: only differences are
// used), with the leave-one-out test of each accepted pair. Empty tests for pairs not accepted.
std::vector<PairTest> TestPairs(const std::vector<Eigen::Vector2d>& stage_px, double stage_sigma_px,
                                const std::vector<PairRegistration>& pairs) {
  const int n = static_cast<int>(stage_px.size());
  const double prior = 1.0 / (stage_sigma_px * stage_sigma_px);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n);
  const auto add_block = [&](int r, int c, const Eigen::Matrix2d& w) {
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) triplets.emplace_back(2 * r + i, 2 * c + j, w(i, j));
    }
  };
  for (int i = 0; i < n; ++i) {
    add_block(i, i, prior * Eigen::Matrix2d::Identity());
    rhs.segment<2>(2 * i) += prior * stage_px[static_cast<size_t>(i)];
  }
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    const Eigen::Matrix2d& w = pair.information;
    add_block(pair.a, pair.a, w);
    add_block(pair.b, pair.b, w);
    add_block(pair.a, pair.b, -w);
    add_block(pair.b, pair.a, -w);
    rhs.segment<2>(2 * pair.a) -= w * pair.offset_px;
    rhs.segment<2>(2 * pair.b) += w * pair.offset_px;
  }
  Eigen::SparseMatrix<double> normal(2 * n, 2 * n);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) throw std::runtime_error("loop check: singular normal equations");
  const Eigen::VectorXd x = solver.solve(rhs);
  std::vector<PairTest> tests(pairs.size());
  Eigen::VectorXd column = Eigen::VectorXd::Zero(2 * n);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const PairRegistration& pair = pairs[k];
    if (!pair.accepted && pair.unmoved) continue;
    // H = A N^-1 A': the covariance of p_b - p_a in the solve with every pair.
    Eigen::Matrix2d h;
    for (int j = 0; j < 2; ++j) {
      column.setZero();
      column(2 * pair.a + j) = -1.0;
      column(2 * pair.b + j) = 1.0;
      const Eigen::VectorXd z = solver.solve(column);
      h.col(j) = z.segment<2>(2 * pair.b) - z.segment<2>(2 * pair.a);
    }
    h = 0.5 * (h + h.transpose()).eval();
    PairTest& t = tests[k];
    if (!pair.accepted) {
      // Not in the solve: the others' prediction is the solve's.
      t.predicted = x.segment<2>(2 * pair.b) - x.segment<2>(2 * pair.a);
      t.prediction_covariance = h;
      continue;
    }
    const Eigen::Matrix2d& w = pair.information;
    const Eigen::Matrix2d identity = Eigen::Matrix2d::Identity();
    const Eigen::Vector2d residual = pair.offset_px - (x.segment<2>(2 * pair.b) - x.segment<2>(2 * pair.a));
    t.chi_square = residual.dot(w * residual);
    // Deleted residual (I - H W)^-1 r, and the covariance of the others' prediction D = H (I - W H)^-1.
    t.misclosure = Decompose<Eigen::PartialPivLU<Eigen::Matrix2d>>(Eigen::Matrix2d(identity - h * w),
                                                                  "a pair's deleted residual").solve(residual);
    t.prediction_covariance = h * (identity - w * h).inverse();
    t.prediction_covariance = 0.5 * (t.prediction_covariance + t.prediction_covariance.transpose()).eval();
    t.predicted = pair.offset_px - t.misclosure;
    t.statistic = t.misclosure.dot(Decompose<Eigen::PartialPivLU<Eigen::Matrix2d>>(
        Eigen::Matrix2d(identity + w * t.prediction_covariance), "a pair's misclosure test").solve(w * t.misclosure));
    t.misclosure_px = (DeterminedDirections(w) * t.misclosure).norm();
    const Eigen::Matrix2d determined = DeterminedDirections(w);
    t.redundancy = determined.trace() - (w * h).trace();
  }
  return tests;
}

double LargestSigma(const Eigen::Matrix2d& covariance) {
  const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(covariance, "a position's covariance");
  return std::sqrt(std::max(0.0, eig.eigenvalues()(1)));
}

// (W^-1 + S)^-1 for a possibly singular information W: W (I + S W)^-1.
Eigen::Matrix2d WidenedInformation(const Eigen::Matrix2d& w, const Eigen::Matrix2d& spread) {
  const Eigen::Matrix2d widened = w * (Eigen::Matrix2d::Identity() + spread * w).inverse();
  return 0.5 * (widened + widened.transpose());
}

// The pair the loops contradict most, searched again where they put it or dropped; repeated until none is
// contradicted beyond options' thresholds.
void OverruleWorst(const std::vector<Eigen::Vector2d>& stage_px, double stage_sigma_px,
                   std::vector<PairRegistration>& pairs, const ResearchPair& research, const LoopCheckOptions& options,
                   LoopCheck& check) {
  const double min_statistic = options.min_sigmas * options.min_sigmas;
  for (size_t round = 0; round < pairs.size(); ++round) {
    const std::vector<PairTest> tests = TestPairs(stage_px, stage_sigma_px, pairs);
    double worst = 0.0;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (!pairs[k].accepted || tests[k].misclosure_px < options.min_misclosure_px) continue;
      if (tests[k].statistic > min_statistic) worst = std::max(worst, tests[k].statistic);
    }
    if (worst == 0.0) break;
    // The suspects: pairs that explain the misclosures about as well as the worst one.
    std::vector<size_t> suspects;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (!pairs[k].accepted || tests[k].misclosure_px < options.min_misclosure_px) continue;
      if (tests[k].statistic > min_statistic && tests[k].statistic >= options.tie_fraction * worst) suspects.push_back(k);
    }
    // Each searched again where the others put it; one that registers there, away from where it was, is the
    // wrong one (the best match there, when several do). Where none does, the weakest is dropped.
    size_t chosen = suspects.front();
    bool replaced = false;
    PairRegistration replacement;
    for (const size_t k : suspects) {
      const PairTest& t = tests[k];
      const Eigen::Vector2d spread = t.prediction_covariance.diagonal().cwiseSqrt();
      const Eigen::Vector2d window = (4.0 * spread).cwiseMax(3.0);
      PairRegistration again = research(pairs[k], t.predicted, window);
      again.a = pairs[k].a;
      again.b = pairs[k].b;
      if (!again.accepted) continue;
      const bool near_prediction =
          ((again.offset_px - t.predicted).cwiseAbs() - window).maxCoeff() <= 0.0 &&
          (again.offset_px - t.predicted).norm() <= std::max(options.min_misclosure_px, 3.0 * LargestSigma(t.prediction_covariance));
      const bool moved = (again.offset_px - pairs[k].offset_px).norm() >= 1.0;
      if (!near_prediction || !moved) continue;
      if (!replaced || again.quality > replacement.quality) {
        chosen = k, replaced = true, replacement = again;
      }
    }
    if (!replaced) {
      for (const size_t k : suspects) {
        if (pairs[k].quality < pairs[chosen].quality) chosen = k;
      }
    }
    OverruledPair record;
    record.pair = static_cast<int>(chosen);
    record.registered_px = pairs[chosen].offset_px;
    record.predicted_px = tests[chosen].predicted;
    record.misclosure_sigma = std::sqrt(tests[chosen].statistic);
    record.replaced = replaced;
    if (replaced) {
      replacement.nominal_px = pairs[chosen].nominal_px;
      pairs[chosen] = replacement;
    } else {
      pairs[chosen].accepted = false;
      pairs[chosen].rejection = "overruled by the loops: " + record.Text();
    }
    check.overruled.push_back(record);
  }

}

// Rejected pairs (not the unmoved ones) whose tiles the accepted pairs place to within a few pixels of each other:
// searched again there, within four standard deviations of the prediction; one that registers near it stands.
// Returns how many did.
int RecoverRejected(const std::vector<Eigen::Vector2d>& stage_px, double stage_sigma_px,
                    std::vector<PairRegistration>& pairs, const ResearchPair& research, const LoopCheckOptions& options,
                    std::vector<bool>& tried, LoopCheck& check) {
  const std::vector<PairTest> tests = TestPairs(stage_px, stage_sigma_px, pairs);
  int recovered = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].accepted || pairs[k].unmoved || tried[k]) continue;
    const PairTest& t = tests[k];
    if (!(LargestSigma(t.prediction_covariance) <= options.recover_within_px)) continue;
    tried[k] = true;
    const Eigen::Vector2d window = (4.0 * t.prediction_covariance.diagonal().cwiseSqrt()).cwiseMax(3.0);
    PairRegistration again = research(pairs[k], t.predicted, window);
    again.a = pairs[k].a;
    again.b = pairs[k].b;
    if (!again.accepted || (again.offset_px - t.predicted).norm() >
                               std::max(options.min_misclosure_px, 3.0 * LargestSigma(t.prediction_covariance))) {
      continue;
    }
    again.nominal_px = pairs[k].nominal_px;
    pairs[k] = again;
    check.recovered.push_back(static_cast<int>(k));
    ++recovered;
  }
  return recovered;
}

}  // namespace

double UncertaintyScale(double birge_ratio, double dof) {
  // The loops' redundancy is a count; the stage prior's weak pull makes the solve's effective degrees of freedom miss
  // it by a hair (a ring of 8 tiles around a blank one: 2.0000002, which scaled every pair's u by 1400).
  dof = std::round(dof);
  if (!(dof > 2.0)) return std::max(1.0, birge_ratio);
  return birge_ratio * std::sqrt(dof / (dof - 2.0));
}

std::string OverruledPair::Text() const {
  char text[320];
  std::snprintf(text, sizeof text,
                "its offset %.2f, %.2f px disagrees with what the loops of the grid put there (%.2f, %.2f px) by %.1f "
                "standard deviations: %s",
                registered_px.x(), registered_px.y(), predicted_px.x(), predicted_px.y(), misclosure_sigma,
                replaced ? "registered again there" : "nothing registers there, dropped");
  return text;
}

LoopCheck CheckPairsAgainstLoops(const std::vector<Eigen::Vector2d>& stage_px, double stage_sigma_px,
                                 std::vector<PairRegistration>& pairs, const ResearchPair& research,
                                 const LoopCheckOptions& options) {
  if (!(stage_sigma_px > 0.0)) throw std::invalid_argument("CheckPairsAgainstLoops: the stage sigma must be positive");
  LoopCheck check;
  // Overrule until the loops close, then search the rejected pairs where the loops put them; what that recovers
  // closes more loops, so again, until nothing changes (each pair is recovered at most once).
  std::vector<bool> tried(pairs.size(), false);
  for (size_t pass = 0; pass <= pairs.size(); ++pass) {
    OverruleWorst(stage_px, stage_sigma_px, pairs, research, options, check);
    if (RecoverRejected(stage_px, stage_sigma_px, pairs, research, options, tried, check) == 0) break;
  }

  // What remains: the misclosures against the stated precision.
  const std::vector<PairTest> tests = TestPairs(stage_px, stage_sigma_px, pairs);
  double chi_square = 0.0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    // The pairs that claim a precision in both directions: along machining marks a pair's rank-one information,
    // tilted by its noise, weighs a residual that is whatever the noise put there, not a misclosure.
    if (!pairs[k].accepted) continue;
    const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(pairs[k].information, "a pair's information");
    const Eigen::Vector2d lambda = eig.eigenvalues();
    if (!(lambda(0) >= 1e-2 * lambda(1))) continue;
    chi_square += tests[k].chi_square;
    check.dof += tests[k].redundancy;
  }
  if (check.dof >= 1.0) check.birge_ratio = std::sqrt(chi_square / check.dof);
  // Up or down: a pair's information comes from its overlap's gradients and noise; on the cut real tiles of issue 42
  // it claimed 0.03-0.05 px where the loops and the truth showed 0.01 px.
  check.uncertainty_scale = UncertaintyScale(check.birge_ratio, check.dof);
  for (size_t k = 0; k < pairs.size(); ++k) {
    PairRegistration& pair = pairs[k];
    if (!pair.accepted) continue;
    if (!pair.ambiguous) continue;
    // An ambiguous pair: the places that matched about as well as the chosen one. Where the others predict the
    // pair well enough to tell them apart, the loops decided; otherwise its offset is any of them.
    double best = pair.quality;
    for (const auto& c : pair.candidates) best = std::max(best, c.ncc);
    Eigen::Matrix2d spread = Eigen::Matrix2d::Zero();
    int alternatives = 0;
    bool decided = true;
    // Only places apart along what the pair determines: along machining marks every place on the ridge matches,
    // and the stage, not the pair, holds that direction.
    const Eigen::Matrix2d determined = DeterminedDirections(pair.information);
    for (const auto& c : pair.candidates) {
      const Eigen::Vector2d d = determined * (c.offset_px - pair.offset_px);
      if (d.norm() < 3.0 || c.ncc < best - options.ambiguous_ncc) continue;
      spread += d * d.transpose();
      ++alternatives;
      decided = decided && d.norm() > 4.0 * LargestSigma(tests[k].prediction_covariance);
    }
    if (alternatives > 0 && !decided) {
      pair.information = WidenedInformation(pair.information, spread / (alternatives + 1.0));
    }
  }
  return check;
}

}  // namespace fvm::imaging
