#include "imaging/focus_stack_alignment.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <string>
#include <type_traits>
#include <variant>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

// Registration runs on a copy at most this wide: breathing and shifts are smooth over the image, and the
// enhanced correlation's cost grows with the pixels.
constexpr int kRegistrationWidth = 800;
constexpr double kRegistrationBlurPx = 3.0;

int CvDepth(const StackImageView& image) {
  return std::visit(
      [](auto span) {
        using T = std::remove_const_t<typename decltype(span)::element_type>;
        return std::is_same_v<T, std::uint8_t> ? CV_8U : std::is_same_v<T, std::uint16_t> ? CV_16U : CV_32F;
      },
      image.pixels);
}

cv::Mat Wrap(const StackImageView& image) {
  const void* data = std::visit([](auto span) { return static_cast<const void*>(span.data()); }, image.pixels);
  // OpenCV only reads through this header; it lacks a const Mat type.
  return cv::Mat(image.height, image.width, CV_MAKETYPE(CvDepth(image), image.channels), const_cast<void*>(data));
}

cv::Matx33d ToMatrix(const FrameTransform& a) { return {a[0], a[1], a[2], a[3], a[4], a[5], 0, 0, 1}; }

FrameTransform FromMatrix(const cv::Matx33d& m) { return {m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2)}; }

}  // namespace

FrameTransform FocusStackAligner::Register(const StackImageView& grey) {
  const cv::Mat image = Wrap(grey);
  if (grey.channels != 1) throw InputError("focus stack alignment: a grey image is needed");
  const double scale = std::min(1.0, double(kRegistrationWidth) / double(grey.width));
  cv::Mat small;
  image.convertTo(small, CV_32F);
  if (scale < 1.0) cv::resize(small, small, cv::Size(), scale, scale, cv::INTER_AREA);
  // Neighbours differ in focus: smoothed alike, their sharp and blurred parts correlate.
  cv::GaussianBlur(small, small, cv::Size(), kRegistrationBlurPx, 0.0, cv::BORDER_REFLECT);
  const int index = count_++;
  if (index == 0) {
    width_ = grey.width, height_ = grey.height;
  } else if (grey.width != width_ || grey.height != height_) {
    throw InputError("image " + std::to_string(index + 1) + " of the stack: " + std::to_string(grey.width) + " x " +
                     std::to_string(grey.height) + " px, unlike the first image's " + std::to_string(width_) + " x " +
                     std::to_string(height_) + " px");
  }
  if (index > 0) {
    const cv::Mat previous(small.rows, small.cols, CV_32F, previous_.data());
    cv::Mat warp = cv::Mat::eye(2, 3, CV_32F);
    try {
      cv::findTransformECC(previous, small, warp, cv::MOTION_AFFINE,
                           cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-6), cv::noArray(),
                           1);
    } catch (const cv::Exception&) {
      // No common sharp texture (both images far out of focus, or a texture-free scene): the image is taken
      // where the previous one was, and counted.
      ++unregistered_;
      previous_.assign(small.ptr<float>(), small.ptr<float>() + small.total());
      return from_first_;
    }
    // The map from the previous image into this one, at full resolution: S^-1 W S with S the scaling.
    cv::Matx33d w(warp.at<float>(0, 0), warp.at<float>(0, 1), warp.at<float>(0, 2), warp.at<float>(1, 0),
                  warp.at<float>(1, 1), warp.at<float>(1, 2), 0, 0, 1);
    const cv::Matx33d s(scale, 0, 0, 0, scale, 0, 0, 0, 1), s_inv(1 / scale, 0, 0, 0, 1 / scale, 0, 0, 0, 1);
    from_first_ = FromMatrix(s_inv * w * s * ToMatrix(from_first_));
  }
  previous_.assign(small.ptr<float>(), small.ptr<float>() + small.total());
  return from_first_;
}

StackImage FocusStackAligner::Warp(const StackImageView& image, const FrameTransform& from_first) {
  const cv::Mat source = Wrap(image);
  cv::Mat out;
  const cv::Matx23d m(from_first[0], from_first[1], from_first[2], from_first[3], from_first[4], from_first[5]);
  cv::warpAffine(source, out, m, source.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  StackImage result;
  result.width = image.width;
  result.height = image.height;
  result.channels = image.channels;
  std::visit(
      [&](auto span) {
        using T = std::remove_const_t<typename decltype(span)::element_type>;
        result.pixels = std::vector<T>(out.ptr<T>(), out.ptr<T>() + out.total() * std::size_t(image.channels));
      },
      image.pixels);
  return result;
}

}  // namespace fvm::imaging
