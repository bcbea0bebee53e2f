#pragma once
// Sub-pixel registration of two prepared crops: Lanczos-4 resampling and its exact gradient, and Gauss-Newton on
// the squared difference.
// Inside imaging/ only (OpenCV types): the public interface is tile_pair_registration.h.

#include <Eigen/Core>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "imaging/tile_prefilter.h"

namespace fvm::imaging::detail {

// The gradient of an image as Lanczos-4 interpolates it, at the pixels.
void InterpolationGradient(const cv::Mat& image, cv::Mat& gx, cv::Mat& gy);
// A sampled at v + e for every v of `inner` (B's frame); `inner` must keep 4 px of A around it after the shift.
cv::Mat ShiftedCrop(const cv::Mat& a, const Eigen::Vector2d& e, const cv::Rect& inner);
// B's interior: `margin` px in from every side, never into a thin overlap's mirrored context.
std::optional<cv::Rect> Interior(const Prepared& prepared, int margin);
// Where a pixel of `inner` counts (valid in B, and in A wherever the resampling reaches); empty when both whole.
cv::Mat Usable(const cv::Mat& a_valid, const cv::Mat& b_valid, const Eigen::Vector2d& e, const cv::Rect& inner);

// Sub-pixel shift by inverse-compositional Gauss-Newton on sum (A(v + e) - B(v))^2 over B's interior: the
// Jacobian is B's gradient, so it and the 2 x 2 normal matrix are computed once; each step only resamples A.
// Pixels that are not usable (invalid in either crop) are left out, their set fixed at the start of each
// interior. `e` changes only when it settles.
enum class Refinement {
  kSettled,     // a step below the tolerance
  kNoRoom,      // the overlap leaves no interior for the shift
  kNoTexture,   // B has no gradient energy
  kWandered,    // moved more than 4 px from the start: another match than the correlation's peak
  kNotSettled,  // the iterations ran out with steps still above the tolerance
};
// When it does not settle, `last_step` (if given) holds the last step and `e` is left alone.
Refinement RefineShift(const Prepared& a, const Prepared& b, double tolerance_px, Eigen::Vector2d& e,
                       Eigen::Vector2d* last_step = nullptr, Eigen::Vector2d* last_estimate = nullptr);

}  // namespace fvm::imaging::detail
