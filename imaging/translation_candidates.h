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

// The normalised cross-correlation of two prepared crops of one size where b's pixel u meets a's pixel u + e.
double OverlapNcc(const Prepared& a, const Prepared& b, const Eigen::Vector2i& e, int& pixels);
// Candidate offsets within `search` (per axis) of `nominal`, best first; `ambiguous` when another place matches
// within ambiguous_ncc of the best (the one nearest `nominal` then goes first).
std::vector<TranslationCandidate> SearchCandidates(const TileImage& a, const TileImage& b,
                                                   const Eigen::Vector2d& nominal, const Eigen::Vector2d& search,
                                                   int peaks, double sigma, double match_sigma,
                                                   double ambiguous_ncc, bool& ambiguous);
// Shift e such that B(v) = A(v + e), from the phase correlation of same-sized crops, and its peak response.
std::pair<Eigen::Vector2d, double> PhaseShift(const cv::Mat& a, const cv::Mat& b);

}  // namespace fvm::imaging::detail
