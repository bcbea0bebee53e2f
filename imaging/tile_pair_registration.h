#pragma once
// Registration of one pair of overlapping tiles: the translation between them by phase correlation of the
// overlap, refined to sub-pixel by Gauss-Newton on Lanczos-4 resampling, with a quality and an inverse
// covariance. Invalid pixels (NaN) are left out. tile_registration.h places whole grids from such pairs.
//
// Pixel frame: x to the right (+X), y down (-Y, row 0 of an image is its highest Y); an offset is where b's
// top-left corner lies in a's frame.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/overlap_height_step.h"  // the z step of a registered pair of height-map tiles

namespace fvm::imaging {

// An overlap whose narrow side is below this is thin: its crops are mirrored out for the refinement's margins,
// and a grid sends its pairs straight to the widened search (SearchPair), where the nominal overlap's lone
// phase-correlation peak of a sparse, thin overlap was a pixel or more off often enough.
constexpr int kThinOverlapPx = 24;

struct RegistrationOptions {
  // Pairs whose quality (the normalised cross-correlation of the high-passed overlap once aligned) falls below
  // this are rejected. The same scene under 3 % noise and 30 % vignetting gives > 0.9; unrelated overlaps of a
  // few thousand pixels reach 0.3 at their best shift. The phase-correlation peak (`response`) is no test: it
  // ranged 0.04-0.9 on good pairs and up to 0.4 on unrelated ones in the tests.
  double min_quality = 0.5;
  // The first pass (RegisterPair) correlates the nominal overlap only, and rejects a shift farther from the
  // nominal one than this fraction of the overlap's narrow side: the correlation is periodic over the crop, so
  // shifts near half of it are as likely wrapped as real.
  double max_correction = 0.35;
  // The widened search (SearchPair; RegisterTileGrid sends it thin overlaps, and the pairs the first pass
  // rejects or the stage model disputes): how far a pair's offset may lie from its nominal one, per axis, as a
  // fraction of the tile's size along that axis (0.1: 24 px of a 245 px wide tile). The candidates are searched over the nominal overlap widened by this
  // much on every side, so that a stage that steps a few pixels long or drifts sideways is found, not assumed
  // away; 0.5 searches the whole pair. A grid's second pass searches a few repeatabilities of the stage model
  // instead (RegisterTileGrid).
  double search_fraction = 0.1;
  // Phase-correlation peaks kept as candidates; each is tested, with its wrap-around interpretations inside the
  // window, by the normalised cross-correlation of the overlap it implies, and the best one is refined. Thin,
  // sparse overlaps put the true peak below a few spurious ones (edges, noise) often enough that one is not
  // enough.
  int candidate_peaks = 8;
  // The last search of a pair no window around the nominal offset registered (and the stage model's window, when
  // its repeatability is that large): the whole plausible range, per axis this fraction of the tile (0.25: 148 px
  // of a 594 px wide tile). A strip of real camera tiles stepped 242-358 px for a nominal 297; beyond a quarter of
  // a tile a stage is broken, not imprecise.
  double wide_search_fraction = 0.25;
  // Candidates and the quality are judged on the high-passed crops smoothed by this Gaussian (px) as well: where
  // the camera's pixel noise is as strong as the texture at the finest scale, the aligned overlap of a real strip
  // correlated 0.06-0.29 in the raw high-pass and its wrong candidates nearly as well. 0: the high-pass alone.
  double match_sigma_px = 2.0;
  // ... and high-passed at this scale (px) only, 0: only the shading's quadratic taken out, so that they compare
  // the scene's coarse structure as well (grid lines, pen strokes, dots). On the real strip a wrong offset near
  // the nominal one correlated 0.91 in the 2-32 px band and 0.80 in the 2-8 px band, where the values as stored
  // correlate 0.32 there and 0.79 at the true offset.
  double match_highpass_sigma_px = 0.0;
  // Two candidates at least 3 px apart whose correlations differ by less than this are ambiguous (a repeating
  // pattern: a printed grid matches its lines one period off): the pair takes the one nearest the stage's
  // prediction, says so (`ambiguous`), and the stage model is learnt from the pairs that are not.
  double ambiguous_ncc = 0.05;
  // Correlate the (nominal or widened) overlap (true) or the whole frames, one peak, with no second search
  // (false: the baseline of the benchmark, slower and noisier, since most of each frame has nothing to match).
  bool crop_to_overlap = true;
  // Refine the phase-correlation peak by Gauss-Newton on the overlap (Lanczos-4 resampling): the peak's centroid
  // alone is biased towards whole pixels by up to ~0.1 px.
  bool refine = true;
  // High-pass scale (px) applied before matching, so that uneven illumination and tilt do not correlate.
  double highpass_sigma_px = 8.0;
  // How far (px, standard deviation) a tile may be from its nominal position: the stage's error over the grid.
  // Along directions the images determine it moves nothing (their precision is ~0.01 px); along directions they
  // do not (a texture of parallel marks), it keeps the tile near its stage position.
  double stage_sigma_px = 2.0;
  // Register the pairs of a grid on OpenCV's thread pool (false: one thread, the benchmark's baseline). The
  // result is the same either way.
  bool parallel = true;
  void Check() const;  // throws std::invalid_argument for values outside their ranges
};

// One translation the phase correlation proposes for a pair, tested on the overlap it implies.
struct TranslationCandidate {
  Eigen::Vector2d offset_px = Eigen::Vector2d::Zero();  // b's top-left in a's frame, whole pixels
  double peak = 0.0;     // the phase-correlation peak it comes from
  double ncc = 0.0;      // normalised cross-correlation of the high-passed overlap at this offset
  int overlap_px = 0;    // pixels of that overlap
};

struct PairRegistration {
  int a = 0, b = 0;                                     // tile indices
  Eigen::Vector2d nominal_px = Eigen::Vector2d::Zero();  // b's top-left in a's frame, from the stage / grid
  Eigen::Vector2d offset_px = Eigen::Vector2d::Zero();   // measured, when accepted
  double response = 0.0;  // phase-correlation peak
  double quality = 0.0;   // normalised cross-correlation once aligned, in [-1, 1]
  // The offset's inverse covariance (px^-2), the pair's weight in the solve: from the texture the two tiles
  // share (the cross products of their gradients, which their independent noise leaves alone) and the residual
  // variance, with a floor of 0.005 px. A direction along which the texture does not change (machining marks, a
  // polished face) carries none: the overlap cannot tell a shift along it, and the stage decides it.
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
  bool accepted = false;
  // The candidates that lay inside the search window, best (highest ncc) first; the first is what was refined.
  // A first-pass pair (RegisterPair) reports its single candidate, the refined nominal overlap's peak.
  std::vector<TranslationCandidate> candidates;
  bool searched = false;  // its offset comes from the widened search (SearchPair), not the first pass
  // Another candidate matched within ambiguous_ncc of the chosen one: the choice rests on the stage's prediction.
  bool ambiguous = false;
  // The tiles matched one on the other (no motion) better than at any offset the stage allows: no search registers
  // them (RegisterPairOverRange).
  bool unmoved = false;
  Eigen::Vector2d search_px = Eigen::Vector2d::Zero();  // the window's half-width per axis
  // Why the pair was rejected, for people (empty when accepted): the overlap too small, the shift implausible,
  // the sub-pixel refinement not settling, the quality below the threshold, or no texture to fix the shift.
  std::string rejection;
};

// Where b's top-left corner lies in a's pixel frame: the first pass, over the nominal overlap only. Rejected
// (accepted = false, `rejection` says why) when the nominal overlap is smaller than 8 x 8 px, the shift is farther
// than max_correction allows, the sub-pixel refinement does not settle, the quality is below the threshold, or
// the texture's gradient energy stands out of the noise's in no direction.
PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options);
// The first pass of a grid or a chain: RegisterPair, checked against the overlap NCC at every offset within
// range_px (per axis) of nominal_px (the whole plausible range, RegistrationOptions::wide_search_fraction): where
// the range's best match lies elsewhere, that one is refined instead (`searched`, with its `candidates`); where
// the tiles match one on the other better than anywhere in the range, rejected (`unmoved`). A pair whose range had
// one clear peak is fixed by it along every direction (a direction its gradients leave out carries half a pixel).
PairRegistration RegisterPairOverRange(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                                       const Eigen::Vector2d& range_px, const RegistrationOptions& options);
// The same searched within search_px (per axis) of nominal_px: candidates from the phase correlation of the
// widened overlap, tested by NCC, the best refined. Rejected also when no candidate lies in the window.
PairRegistration SearchPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                            const Eigen::Vector2d& search_px, const RegistrationOptions& options);

}  // namespace fvm::imaging
