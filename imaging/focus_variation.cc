#include "imaging/focus_variation.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Rows per stripe. Fixed (not derived from the thread count) so that the parallel and the single-threaded run
// filter exactly the same bands and give the same bits.
constexpr int kStripeRows = 32;

std::string Describe(std::string_view name, int index) {
  return name.empty() ? "image " + std::to_string(index + 1) + " of the stack" : std::string(name);
}

cv::Mat WrapPixels(const StackImageView& image) {
  return std::visit(
      [&](auto span) {
        using T = typename decltype(span)::element_type;
        const int type = std::is_same_v<T, const std::uint8_t> ? CV_8U : std::is_same_v<T, const std::uint16_t> ? CV_16U : CV_32F;
        // OpenCV never writes through this header; it only lacks a const Mat type.
        return cv::Mat(image.height, image.width, type, const_cast<void*>(static_cast<const void*>(span.data())));
      },
      image.pixels);
}

std::size_t PixelCount(const StackImageView& image) {
  return std::visit([](auto span) { return span.size(); }, image.pixels);
}

// The focus measure of a band of rows (float, same size). The band carries a margin of rows beyond the rows
// that are kept, so that the filters see real neighbours there; at the image's own edges they reflect.
cv::Mat MeasureBand(const cv::Mat& band, FocusMeasure measure, int window) {
  cv::Mat grey;
  band.convertTo(grey, CV_32F);
  cv::Mat out;
  const cv::Size box(window, window);
  switch (measure) {
    case FocusMeasure::kModifiedLaplacian: {
      cv::Mat lx, ly;
      cv::Sobel(grey, lx, CV_32F, 2, 0, 1, 1.0, 0.0, cv::BORDER_REFLECT);  // ksize 1: the bare [1 -2 1]
      cv::Sobel(grey, ly, CV_32F, 0, 2, 1, 1.0, 0.0, cv::BORDER_REFLECT);
      cv::Mat ml = cv::abs(lx) + cv::abs(ly);
      cv::boxFilter(ml, out, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
      break;
    }
    case FocusMeasure::kTenengrad: {
      cv::Mat gx, gy;
      cv::Sobel(grey, gx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REFLECT);
      cv::Sobel(grey, gy, CV_32F, 0, 1, 3, 1.0, 0.0, cv::BORDER_REFLECT);
      cv::Mat energy = gx.mul(gx) + gy.mul(gy);
      cv::boxFilter(energy, out, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
      break;
    }
    case FocusMeasure::kVariance: {
      // Shifted by the band's mean first: E[I^2] - E[I]^2 in float loses everything to cancellation when the
      // grey level is large against the contrast (16-bit images).
      grey -= cv::mean(grey)[0];
      cv::Mat mean, mean_sq;
      cv::boxFilter(grey, mean, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
      cv::boxFilter(grey.mul(grey), mean_sq, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
      out = cv::max(mean_sq - mean.mul(mean), 0.0);
      break;
    }
  }
  return out;
}

// The vertex of the parabola through (z0, f0), (z1, f1), (z2, f2), with f1 the largest; z1 when the three are
// not a maximum (flat or collinear). Stays between z0 and z2.
double Vertex(double z0, double z1, double z2, double f0, double f1, double f2) {
  const double a = (z1 - z0) * (f1 - f2), b = (z1 - z2) * (f1 - f0);
  const double denominator = a - b;
  if (!(std::abs(denominator) > 0.0)) return z1;
  const double z = z1 - 0.5 * ((z1 - z0) * a - (z1 - z2) * b) / denominator;
  if (!std::isfinite(z)) return z1;
  return std::clamp(z, std::min(z0, z2), std::max(z0, z2));
}

template <typename Body>
void ForStripes(int rows, bool parallel, const Body& body) {
  const int stripes = (rows + kStripeRows - 1) / kStripeRows;
  const auto run = [&](const cv::Range& range) {
    for (int s = range.start; s < range.end; ++s) body(s * kStripeRows, std::min(rows, (s + 1) * kStripeRows));
  };
  if (parallel) {
    cv::parallel_for_(cv::Range(0, stripes), run);
  } else {
    run(cv::Range(0, stripes));
  }
}

}  // namespace

std::string FocusMeasureName(FocusMeasure measure) {
  switch (measure) {
    case FocusMeasure::kModifiedLaplacian:
      return "laplacian";
    case FocusMeasure::kTenengrad:
      return "tenengrad";
    case FocusMeasure::kVariance:
      return "variance";
  }
  return "?";
}

std::optional<FocusMeasure> ParseFocusMeasure(std::string_view name) {
  for (FocusMeasure m : {FocusMeasure::kModifiedLaplacian, FocusMeasure::kTenengrad, FocusMeasure::kVariance}) {
    if (name == FocusMeasureName(m)) return m;
  }
  return std::nullopt;
}

void FocusVariationOptions::Check() const {
  if (window < 3 || window > 51 || window % 2 == 0) {
    throw InputError("focus variation: the window must be an odd number of pixels from 3 to 51, not " +
                     std::to_string(window));
  }
  if (!(dx_mm > 0.0) || !std::isfinite(dx_mm) || !(dy_mm >= 0.0) || !std::isfinite(dy_mm)) {
    throw InputError("focus variation: the pixel size must be positive and finite (mm)");
  }
  if (!(min_quality >= 0.0) || !std::isfinite(min_quality)) {
    throw InputError("focus variation: the minimum quality must be 0 or more (peak over mean focus measure)");
  }
}

struct FocusAccumulator::State {
  FocusVariationOptions options;
  int width = 0, height = 0;
  std::vector<double> z;
  // Per pixel: the largest measure so far, its image, the measure in the images before and after it (NaN until
  // seen), the sum over all images (for the mean), and the previous image's measure.
  std::vector<float> best, left, right, sum, previous;
  std::vector<std::int32_t> index;
};

FocusAccumulator::FocusAccumulator(const FocusVariationOptions& options) : state_(std::make_unique<State>()) {
  options.Check();
  state_->options = options;
}

FocusAccumulator::~FocusAccumulator() = default;

int FocusAccumulator::count() const { return static_cast<int>(state_->z.size()); }

void FocusAccumulator::Add(const StackImageView& image, double z_mm, std::string_view name) {
  State& s = *state_;
  const int k = count();
  const std::string what = Describe(name, k);
  if (image.width <= 0 || image.height <= 0 || PixelCount(image) != std::size_t(image.width) * std::size_t(image.height)) {
    throw InputError(what + ": empty image or pixel count that does not match its size");
  }
  if (!std::isfinite(z_mm)) throw InputError(what + ": the z position is not a finite number");
  if (k == 0) {
    const int window = s.options.window;
    if (image.width < window || image.height < window) {
      throw InputError(what + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " px is smaller than the focus window (" + std::to_string(window) + " px)");
    }
    s.width = image.width;
    s.height = image.height;
    const std::size_t n = std::size_t(s.width) * std::size_t(s.height);
    s.best.assign(n, 0.0f);
    s.left.assign(n, kNaN);
    s.right.assign(n, kNaN);
    s.sum.assign(n, 0.0f);
    s.previous.assign(n, kNaN);
    s.index.assign(n, 0);
  } else {
    if (image.width != s.width || image.height != s.height) {
      throw InputError(what + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " px, but the stack's first image is " + std::to_string(s.width) + " x " +
                       std::to_string(s.height) + " px; every image of a stack must have the same size");
    }
    const double step = z_mm - s.z.back();
    const double direction = k >= 2 ? s.z[1] - s.z[0] : step;
    if (step == 0.0) {
      throw InputError(what + ": z = " + std::to_string(z_mm) + " mm repeats the previous image's position; "
                       "each image of a stack needs its own z");
    }
    if ((step > 0.0) != (direction > 0.0)) {
      throw InputError(what + ": z = " + std::to_string(z_mm) + " mm is out of order (previous " +
                       std::to_string(s.z.back()) + " mm); list the images by increasing or decreasing z");
    }
  }
  s.z.push_back(z_mm);

  const cv::Mat pixels = WrapPixels(image);
  // Derivative (1 px) plus box half-width: beyond that, a band's edge does not reach the rows it keeps.
  const int margin = s.options.window / 2 + 1;
  const FocusMeasure measure = s.options.measure;
  const int window = s.options.window;
  ForStripes(s.height, s.options.parallel, [&](int r0, int r1) {
    const int b0 = std::max(0, r0 - margin), b1 = std::min(s.height, r1 + margin);
    const cv::Mat band = MeasureBand(pixels.rowRange(b0, b1), measure, window);
    for (int r = r0; r < r1; ++r) {
      const float* m = band.ptr<float>(r - b0);
      const std::size_t row = std::size_t(r) * std::size_t(s.width);
      for (int c = 0; c < s.width; ++c) {
        const std::size_t i = row + std::size_t(c);
        const float v = m[c];
        if (s.index[i] == k - 1) s.right[i] = v;
        if (k == 0 || v > s.best[i]) {
          s.best[i] = v;
          s.index[i] = k;
          s.left[i] = s.previous[i];
          s.right[i] = kNaN;
        }
        s.sum[i] += v;
        s.previous[i] = v;
      }
    }
  });
}

FocusResult FocusAccumulator::Finish() const {
  const State& s = *state_;
  const int n = count();
  if (n < 3) {
    throw InputError("focus variation: the stack has " + std::to_string(n) +
                     " image(s); at least 3 are needed (a focus peak needs an image on either side of it)");
  }
  FocusResult result;
  HeightMap& map = result.height;
  map.size_x = s.width;
  map.size_y = s.height;
  map.dx_mm = s.options.dx_mm;
  map.dy_mm = s.options.dy_mm > 0.0 ? s.options.dy_mm : s.options.dx_mm;
  map.source = "focus variation (" + FocusMeasureName(s.options.measure) + ", window " +
               std::to_string(s.options.window) + " px, " + std::to_string(n) + " images)";
  const std::size_t size = s.best.size();
  map.z_mm.assign(size, kNaN);
  result.quality.assign(size, 0.0f);
  result.peak_index = s.index;
  const bool gaussian = s.options.peak_fit == PeakFit::kGaussian;
  const float min_quality = static_cast<float>(s.options.min_quality);
  ForStripes(s.height, s.options.parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(s.width); i < std::size_t(r1) * std::size_t(s.width); ++i) {
      const float mean = s.sum[i] / static_cast<float>(n);
      const float quality = mean > 0.0f ? s.best[i] / mean : 0.0f;
      result.quality[i] = quality;
      const int k = s.index[i];
      // A peak at either end may lie beyond the stack: its height is unknown, not the end's z.
      if (k == 0 || k == n - 1 || !(quality >= min_quality)) continue;
      double f0 = s.left[i], f1 = s.best[i], f2 = s.right[i];
      if (gaussian && f0 > 0.0 && f2 > 0.0) {
        f0 = std::log(f0), f1 = std::log(f1), f2 = std::log(f2);
      }
      map.z_mm[i] = static_cast<float>(Vertex(s.z[k - 1], s.z[k], s.z[k + 1], f0, f1, f2));
    }
  });
  return result;
}

FocusResult ReconstructFocusStack(const std::vector<StackImageView>& images, const std::vector<double>& z_mm,
                                  const FocusVariationOptions& options) {
  if (images.size() != z_mm.size()) {
    throw InputError("focus variation: " + std::to_string(images.size()) + " images but " +
                     std::to_string(z_mm.size()) + " z positions");
  }
  FocusAccumulator accumulator(options);
  for (std::size_t i = 0; i < images.size(); ++i) accumulator.Add(images[i], z_mm[i]);
  return accumulator.Finish();
}

}  // namespace fvm::imaging
