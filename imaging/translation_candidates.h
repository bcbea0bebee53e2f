#pragma once
// Where the phase correlation says b may lie in a's frame: its peaks, each tested by the normalised
// cross-correlation of the overlap it implies.
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>
#include <utility>
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "imaging/tile_pair_registration.h"
#include "imaging/tile_prefilter.h"

namespace fvm::imaging::detail {

// The band in which candidates and the quality are judged (RegistrationOptions::match_highpass_sigma_px and
// match_sigma_px): the scene's coarse structure, without the pixel noise.
struct MatchScale {
  double highpass_sigma_px = 0.0;  // 0: the quadratic shading only
  double lowpass_sigma_px = 2.0;
};
// A crop high-passed and smoothed to the matching band.
Prepared MatchingCrop(const cv::Mat& crop, const MatchScale& scale, bool logarithm);
// The normalised cross-correlation in the matching band of the overlap of a and b when b's top-left corner sits at
// `whole` in a's frame: whether the two tiles show the same scene there. 0 when they hardly overlap.
double MatchQuality(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole, const MatchScale& scale);

// The normalised cross-correlation of two prepared crops of one size where b's pixel u meets a's pixel u + e.
double OverlapNcc(const Prepared& a, const Prepared& b, const Eigen::Vector2i& e, int& pixels);
// Candidate offsets within `search` (per axis) of `nominal`, best first; `ambiguous` when another place matches
// within ambiguous_ncc of the best (the one nearest `nominal` then goes first).
std::vector<TranslationCandidate> SearchCandidates(const TileImage& a, const TileImage& b,
                                                   const Eigen::Vector2d& nominal, const Eigen::Vector2d& search,
                                                   int peaks, double sigma, const MatchScale& scale,
                                                   double ambiguous_ncc, bool& ambiguous);
// The whole plausible range of a pair searched at once: candidates from the overlap NCC landscape
// (overlap_ncc_landscape.h) within `search` of `nominal`, judged on the whole tiles in the matching band, on the
// pyramid level. Among those within 0.02 of the best the nearest `nominal` goes first; when another place 3 px or
// more away matches within ambiguous_ncc (a repeating pattern), the nearest of those, and it is `ambiguous`.
struct WideSearch {
  std::vector<TranslationCandidate> candidates;  // the one to take first, then the others best first
  bool ambiguous = false;
  bool sharp = false;        // the first one's NCC falls off along both axes (not a ridge along marks)
  double unmoved_ncc = 0.0;  // the tiles' NCC one on the other (offset 0): where the stage did not move
  int scale = 1;             // full-resolution pixels per pixel of the landscape: the first one's uncertainty
};
WideSearch WideCandidates(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal,
                          const Eigen::Vector2d& search, int peaks, const MatchScale& scale, double ambiguous_ncc);

// Where the overlap NCC in the matching band, on the whole tiles at full resolution, is highest among the whole-pixel
// offsets within `radius` (per axis) of `start`, to a fraction of a pixel by a parabola through the best and its
// neighbours along each axis: a landscape peak located on its level's pixel, polished.
Eigen::Vector2d PolishPeak(const TileImage& a, const TileImage& b, const Eigen::Vector2i& start, int radius,
                           const MatchScale& scale);

// Shift e such that B(v) = A(v + e), from the phase correlation of same-sized crops, and its peak response.
std::pair<Eigen::Vector2d, double> PhaseShift(const cv::Mat& a, const cv::Mat& b);

}  // namespace fvm::imaging::detail
