#include "imaging/tile_prefilter.h"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <vector>

#include "core/dense_decomposition.h"

namespace fvm::imaging::detail {

cv::Mat View(const TileImage& image) {
  // A read-only header on the Eigen buffer: OpenCV never writes through it.
  return cv::Mat(static_cast<int>(image.rows()), static_cast<int>(image.cols()), CV_32F,
                 const_cast<float*>(image.data()));
}


// A quadratic surface z = c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2 fitted to the valid pixels of the crop
// (every 4th each way) and subtracted: lens shading and a tilted part are smooth across a tile, and a quadratic
// takes them out whole.
namespace {

void SubtractQuadratic(cv::Mat& crop, const cv::Mat& valid) {
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  const double cx = crop.cols / 2.0, cy = crop.rows / 2.0, scale = std::max(cx, cy);
  for (int y = 0; y < crop.rows; y += 4) {
    for (int x = 0; x < crop.cols; x += 4) {
      if (!valid.empty() && valid.at<float>(y, x) == 0.0f) continue;
      const double u = (x - cx) / scale, v = (y - cy) / scale;
      const Eigen::Matrix<double, 6, 1> b = (Eigen::Matrix<double, 6, 1>() << 1, u, v, u * u, u * v, v * v).finished();
      normal += b * b.transpose();
      rhs += b * crop.at<float>(y, x);
    }
  }
  // A crop a few samples thin cannot hold a quadratic: the pseudo-inverse takes what it can.
  const Eigen::Matrix<double, 6, 1> c =
      Decompose<Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 6, 6>>>(normal, "the tile prefilter's quadratic")
          .solve(rhs);
  // Row by row: c0 + c2 v + c5 v^2 + (c1 + c4 v) u + c3 u^2.
  std::vector<float> u(static_cast<size_t>(crop.cols));
  for (int x = 0; x < crop.cols; ++x) u[static_cast<size_t>(x)] = static_cast<float>((x - cx) / scale);
  for (int y = 0; y < crop.rows; ++y) {
    const double v = (y - cy) / scale;
    const auto constant = static_cast<float>(c(0) + c(2) * v + c(5) * v * v);
    const auto linear = static_cast<float>(c(1) + c(4) * v), square = static_cast<float>(c(3));
    float* row = crop.ptr<float>(y);
    for (int x = 0; x < crop.cols; ++x) {
      const float ux = u[static_cast<size_t>(x)];
      row[x] -= constant + (linear + square * ux) * ux;
    }
  }
}

}  // namespace

// A Gaussian blur that ignores invalid pixels (normalised convolution) and marks valid where at least 99 % of
// the kernel's weight fell on valid pixels.
Prepared Blur(const Prepared& in, double sigma) {
  Prepared out;
  out.pad = in.pad;
  if (in.valid.empty()) {
    cv::GaussianBlur(in.value, out.value, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
    return out;
  }
  cv::Mat weight;
  cv::GaussianBlur(in.value, out.value, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);  // invalid are 0
  cv::GaussianBlur(in.valid, weight, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
  cv::threshold(weight, out.valid, 0.99, 1.0, cv::THRESH_BINARY);
  out.value = out.value / cv::max(weight, 1e-6);
  out.value = out.value.mul(out.valid);
  return out;
}

// Removes what does not belong to the scene and differs between two tiles at the same place. Intensity images
// (all pixels positive) are matched in the logarithm, where the camera's shading (vignetting) is a smooth term
// added to the scene rather than a gain on it: the low-pass of shaded texture is the texture's low-pass shifted by
// sigma^2 grad(g) / g, in opposite directions in A and B, and that biased every pair of a row the same way
// (0.010 px a pair under 30 % vignetting, 1 um over 16 tiles of 6 um pixels; below 0.001 px in the logarithm). Then
// the shading and the part's tilt go as a quadratic surface, before the high-pass: a high-pass alone mirrors
// their slope at the crop's edges into a ridge that sits at the same place of both crops and so pins the shift
// to the whole-pixel crop, which along a direction without texture is all there is. Last, a Gaussian high-pass
// removes the rest of the slow changes.
//
// Both crops of a pair must be compared in one domain (MatchingDomain). In the logarithm a pixel the camera
// clipped to black (0) has no value: it is left out like an invalid one.
Prepared HighPass(const cv::Mat& crop, double sigma, bool logarithm) {
  Prepared out;
  crop.convertTo(out.value, CV_32F);
  cv::Mat usable = out.value == out.value;  // NaN is the one value unequal to itself
  if (logarithm) usable &= out.value > 0.0f;
  if (cv::countNonZero(usable) < static_cast<int>(usable.total())) {
    usable.convertTo(out.valid, CV_32F, 1.0 / 255.0);
    out.value.setTo(logarithm ? 1.0f : 0.0f, ~usable);  // log(1) = 0, as invalid pixels are elsewhere
  }
  if (logarithm) cv::log(out.value, out.value);
  SubtractQuadratic(out.value, out.valid);
  if (!out.valid.empty()) out.value = out.value.mul(out.valid);
  if (sigma > 0.0) {
    const Prepared low = Blur({out.value, out.valid}, sigma);
    out.value -= low.value;
    if (!out.valid.empty()) out.value = out.value.mul(out.valid);
  }
  return out;
}

// The domain both crops of a pair are matched in, decided once for the pair: the logarithm (true) when neither
// crop has a negative valid pixel and both have positive ones (intensity images; pixels clipped to black are then
// left out); otherwise the values themselves (height maps). Deciding per crop compared a crop with one black pixel
// linearly against its partner's logarithm, and the shading returned as a bias.
bool MatchingDomain(const cv::Mat& crop_a, const cv::Mat& crop_b) {
  for (const cv::Mat& crop : {crop_a, crop_b}) {
    cv::Mat values = crop;  // tiles are float already: no copy of a whole tile per pair
    if (crop.type() != CV_32F) crop.convertTo(values, CV_32F);
    // The least and the greatest valid (non-NaN: every comparison with NaN is false) pixel, in one pass.
    float low = std::numeric_limits<float>::infinity(), high = -low;
    for (int y = 0; y < values.rows; ++y) {
      const Eigen::Map<const Eigen::ArrayXf> row(values.ptr<float>(y), values.cols);
      const float row_low = row.minCoeff<Eigen::PropagateNumbers>(), row_high = row.maxCoeff<Eigen::PropagateNumbers>();
      low = row_low < low ? row_low : low;  // a row of NaN only gives NaN, which compares false
      high = row_high > high ? row_high : high;
    }
    if (!(low <= high) || !(low >= 0.0f && high > 0.0f)) return false;
  }
  return true;
}

// Where two tiles overlap when b's top-left corner sits at `whole`, both crops prepared; none when the overlap is
// narrower than kMinOverlapPx. Both crops are the overlap exactly, high-passed alike: a crop that reached into one
// tile's own pixels beyond the overlap low-passed other content than its partner's, and biased thin overlaps by a
// pixel. A thin overlap (narrow side below kThinOverlapPx) is then mirrored out by kThinPadPx on every side, both
// crops alike: refinement and quality keep 5-8 px from a crop's edges for the Lanczos taps, which left nothing of
// a 10-15 px overlap.


void MirrorOut(Prepared& crop, int pad) {
  cv::copyMakeBorder(crop.value, crop.value, pad, pad, pad, pad, cv::BORDER_REFLECT);
  if (!crop.valid.empty()) cv::copyMakeBorder(crop.valid, crop.valid, pad, pad, pad, pad, cv::BORDER_REFLECT);
  crop.pad = pad;
}

std::optional<Overlap> CropOverlap(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole,
                                   double sigma, bool mirror_thin) {
  const int dx = whole.x(), dy = whole.y();
  const int x0 = std::max(0, dx), x1 = std::min(static_cast<int>(a.cols()), dx + static_cast<int>(b.cols()));
  const int y0 = std::max(0, dy), y1 = std::min(static_cast<int>(a.rows()), dy + static_cast<int>(b.rows()));
  if (x1 - x0 < kMinOverlapPx || y1 - y0 < kMinOverlapPx) return std::nullopt;
  Overlap out;
  out.in_a = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  out.in_b = cv::Rect(x0 - dx, y0 - dy, out.in_a.width, out.in_a.height);
  const bool logarithm = MatchingDomain(View(a)(out.in_a), View(b)(out.in_b));
  out.a = HighPass(View(a)(out.in_a), sigma, logarithm);
  out.b = HighPass(View(b)(out.in_b), sigma, logarithm);
  if (mirror_thin && std::min(out.in_a.width, out.in_a.height) < kThinOverlapPx) {
    MirrorOut(out.a, kThinPadPx);
    MirrorOut(out.b, kThinPadPx);
  }
  return out;
}

}  // namespace fvm::imaging::detail
