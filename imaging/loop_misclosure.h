#pragma once
// What the loops of a tile grid say about each pair. Right and lower neighbours close loops (four pairs around
// every square of tiles), so every pair's offset is predicted by the others together with the stage: a wrong pair
// (a repeat of the pattern, a speck on a sparse overlap) leaves a misclosure there, and a right one does not.
// Each pair is tested against the prediction of the others (the leave-one-out residual of the global least
// squares, its deleted residual [Cook and Weisberg 1982] with the covariance of both sides); the worst one is
// searched again where the loops put it, and either takes the offset found there or is dropped. Then the
// misclosures that remain measure the pairs' stated precision (the Birge ratio of the solve [Birge 1932]), and a
// pair that could not choose between candidates and that no loop decides carries their spread.
//
// Pixel frame as in tile_registration.h: offsets are b's top-left corner in a's frame.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "imaging/tile_pair_registration.h"

namespace fvm::imaging {

// A pair whose registration the rest of the grid contradicted.
struct OverruledPair {
  int pair = 0;                                            // index into the pairs
  Eigen::Vector2d registered_px = Eigen::Vector2d::Zero();  // the offset it had
  Eigen::Vector2d predicted_px = Eigen::Vector2d::Zero();   // what the other pairs and the stage put there
  double misclosure_sigma = 0.0;  // how far apart, in standard deviations of both
  bool replaced = false;          // searched again near the prediction, and that offset stands; else dropped
  std::string Text() const;       // for people: what was wrong and what was done
};

struct LoopCheck {
  std::vector<OverruledPair> overruled;
  // Rejected pairs that registered when searched where the loops put them (indices into the pairs).
  std::vector<int> recovered;
  // The square root of the pairs' chi-square per degree of freedom after the check (the loops' misclosures against
  // the pairs' stated precision), and the degrees of freedom (the redundancy the loops give); 1 and 0 without loops.
  double birge_ratio = 1.0;
  double dof = 0.0;
  // What the solve multiplies every pair's standard uncertainty by: the Birge ratio, times sqrt(dof / (dof - 2))
  // (UncertaintyScale). The pairs keep their own claims.
  double uncertainty_scale = 1.0;
};

// What the pairs' standard uncertainties are multiplied by, from the loops' Birge ratio R and their degrees of
// freedom: a position's error over an uncertainty scaled by R, itself estimated from `dof` misclosures, follows
// Student's t with dof degrees of freedom (the least-squares estimate and its residuals are independent), whose
// rms is sqrt(dof / (dof - 2)): R times that, so that the standardised errors have an rms of 1 however few the loops.
// With 2 degrees of freedom or fewer the t's variance is unbounded and R says nothing about how far to trust the
// pairs: they are only ever scaled up, by R where it exceeds 1.
double UncertaintyScale(double birge_ratio, double dof);

// A pair searched again within window_px (per axis) of predicted_px; the caller has the images.
using ResearchPair = std::function<PairRegistration(const PairRegistration& pair, const Eigen::Vector2d& predicted_px,
                                                    const Eigen::Vector2d& window_px)>;

struct LoopCheckOptions {
  // A pair is suspect when its misclosure exceeds both (a whole-pixel mistake, well outside both precisions):
  // sub-pixel disagreements between real tiles (a turn of a few tenths of a degree) are the Birge ratio's business.
  double min_misclosure_px = 1.5;
  double min_sigmas = 5.0;
  // Pairs whose test statistic lies within this fraction of the worst one's are explained as well by one as by the
  // other (the four pairs of a lone square share one misclosure): among them the evidence of a search decides.
  double tie_fraction = 0.7;
  // A rejected pair is searched again where the loops put it when they place its two tiles to within this (px,
  // standard deviation): only images, not the stage alone, say where to look.
  double recover_within_px = 3.0;
  // Candidates of an ambiguous pair whose NCC lies within this of the best are places it could be
  // (RegistrationOptions::ambiguous_ncc).
  double ambiguous_ncc = 0.05;
};

// Checks the accepted pairs against the loops, in place: an overruled pair takes what research() found near the
// prediction, or is rejected (`rejection` says why); a rejected pair whose tiles the others place well is searched
// again there (a stage that stepped farther than the first window reached). `stage_px` and `stage_sigma_px` are the prior of every tile.
// Then measures the loops' misclosures against what the pairs claim (LoopCheck::uncertainty_scale), and widens an
// ambiguous pair that no loop decides by its candidates' spread.
LoopCheck CheckPairsAgainstLoops(const std::vector<Eigen::Vector2d>& stage_px, double stage_sigma_px,
                                 std::vector<PairRegistration>& pairs, const ResearchPair& research,
                                 const LoopCheckOptions& options = {});

}  // namespace fvm::imaging
