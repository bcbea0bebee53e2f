#pragma once
// What registration matches: crops of two tiles, taken out of the shading and the part's tilt and high-passed
// alike, with their invalid (NaN) pixels masked.
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "imaging/io/tile_image.h"
#include "imaging/tile_pair_registration.h"  // kThinOverlapPx

namespace fvm::imaging::detail {

// Overlaps narrower than this give no usable correlation peak.
constexpr int kMinOverlapPx = 8;
// Context mirrored around a thin overlap (CropOverlap).
constexpr int kThinPadPx = 8;

// A crop ready for matching: `value` high-passed, 0 where the tile had no valid pixel; `valid` 1 where it had
// one, 0 elsewhere (CV_32F), or empty when every pixel is valid. Focus-variation height maps leave steep flanks
// and dark spots invalid (NaN); intensity tiles have none.
struct Prepared {
  cv::Mat value;
  cv::Mat valid;
  int pad = 0;  // px of context around the overlap on every side (CropOverlap); interiors keep out of it
};

// A read-only OpenCV header on a tile's buffer.
cv::Mat View(const TileImage& image);
// A Gaussian blur that ignores invalid pixels; valid where 99 % of the kernel's weight fell on valid pixels.
Prepared Blur(const Prepared& in, double sigma);
// The crop in the logarithm (intensity) or as it is (heights), a quadratic surface and a Gaussian low-pass removed.
Prepared HighPass(const cv::Mat& crop, double sigma, bool logarithm);
// Whether a pair's crops are matched in the logarithm (both non-negative with positive pixels).
bool MatchingDomain(const cv::Mat& crop_a, const cv::Mat& crop_b);

struct Overlap {
  cv::Rect in_a, in_b;
  Prepared a, b;
};

void MirrorOut(Prepared& crop, int pad);
// The overlap of a and b when b's top-left corner sits at `whole` in a's frame, both crops prepared; none when
// narrower than kMinOverlapPx.
std::optional<Overlap> CropOverlap(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole,
                                   double sigma, bool mirror_thin = true);

}  // namespace fvm::imaging::detail
