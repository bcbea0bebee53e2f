#include "imaging/focus_stack_curves.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace fvm::imaging {
namespace {

constexpr float kNoValue = std::numeric_limits<float>::quiet_NaN();
constexpr double kGaussianWindowSigma = 0.3;  // per px of window: 0.9 px for 3, 1.5 px for 5

// The half-width of a window's kernel: a box's own, a Gaussian's to 2.5 sigma, rounded (2 px for the 3 px window,
// 4 px for the 5 px one): the weights beyond are below 0.2 % of the centre's, and each tap costs time.
int KernelHalfWidth(int window, bool gaussian) {
  return gaussian ? int(std::lround(2.5 * kGaussianWindowSigma * window)) : window / 2;
}

cv::Mat WrapPixels(const StackImageView& image) {
  return std::visit(
      [&](auto span) {
        using T = std::remove_const_t<typename decltype(span)::element_type>;
        const int type = std::is_same_v<T, std::uint8_t> ? CV_8U : std::is_same_v<T, std::uint16_t> ? CV_16U : CV_32F;
        // OpenCV never writes through this header; it only lacks a const Mat type.
        return cv::Mat(image.height, image.width, CV_MAKETYPE(type, image.channels),
                       const_cast<void*>(static_cast<const void*>(span.data())));
      },
      image.pixels);
}

// Scratch images of one thread, kept from stripe to stripe and batch to batch: OpenCV reuses a Mat's memory when
// the size and type repeat, and allocating (and faulting in) fresh pages for every band cost a tenth of the time.
struct Scratch {
  cv::Mat grey, dx, dy, per_pixel, mean_sq;
  // The batch's window measures for the stripe's rows: [image slot][window][row][column].
  std::vector<float> measures;
};

Scratch& ThreadScratch() {
  thread_local Scratch scratch;
  return scratch;
}

// The modified Laplacian |2I - I_left - I_right| + |2I - I_up - I_down| [Nayar 1994] of rows b0..b1 of an image,
// its neighbours taken from the image itself (reflected at its edges, as BORDER_REFLECT does): one pass over the
// pixels in float, which the compiler vectorises.
template <typename T>
void ModifiedLaplacian(const cv::Mat& image, int b0, int b1, cv::Mat& out) {
  const int width = image.cols, last = image.rows - 1;
  out.create(b1 - b0, width, CV_32F);
  for (int r = b0; r < b1; ++r) {
    const T* up = image.ptr<T>(std::max(r - 1, 0));
    const T* row = image.ptr<T>(r);
    const T* down = image.ptr<T>(std::min(r + 1, last));
    float* o = out.ptr<float>(r - b0);
    const auto at = [&](int c) {
      const float x = 2.0f * float(row[c]);
      const float left = float(row[c > 0 ? c - 1 : 0]), right = float(row[c < width - 1 ? c + 1 : width - 1]);
      return std::abs(x - left - right) + std::abs(x - float(up[c]) - float(down[c]));
    };
    o[0] = at(0);
    for (int c = 1; c < width - 1; ++c) {
      const float x = 2.0f * float(row[c]);
      o[c] = std::abs(x - float(row[c - 1]) - float(row[c + 1])) + std::abs(x - float(up[c]) - float(down[c]));
    }
    if (width > 1) o[width - 1] = at(width - 1);
  }
}

// The measure per pixel of rows b0..b1 before it is averaged over a window: the modified Laplacian (of the image
// smoothed by the pre-filter, see focus_stack_curves.h) or the gradient energy; for the variance the grey levels
// themselves (shifted by the band's mean: E[I^2] - E[I]^2 in float loses everything to cancellation when the grey
// level is large against the contrast, as in 16-bit images).
const cv::Mat& PixelMeasure(const cv::Mat& image, int b0, int b1, FocusMeasure measure, Scratch& b) {
  if (measure == FocusMeasure::kModifiedLaplacian) {
    // The rows the Laplacian reads (one beyond the band) and the pre-filter's reach beyond them, smoothed apart
    // from the rest of the image: rows within its reach of a cut that is not the image's edge are not read.
    const int reach = kPrefilterHalfWidth + 1;
    const int p0 = std::max(0, b0 - reach), p1 = std::min(image.rows, b1 + reach);
    image.rowRange(p0, p1).convertTo(b.grey, CV_32F);
    const int side = 2 * kPrefilterHalfWidth + 1;
    cv::GaussianBlur(b.grey, b.dx, cv::Size(side, side), kPrefilterSigmaPx, kPrefilterSigmaPx, cv::BORDER_REFLECT);
    ModifiedLaplacian<float>(b.dx, b0 - p0, b1 - p0, b.per_pixel);
    return b.per_pixel;
  }
  image.rowRange(b0, b1).convertTo(b.grey, CV_32F);
  if (measure == FocusMeasure::kTenengrad) {
    cv::Sobel(b.grey, b.dx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(b.grey, b.dy, CV_32F, 0, 1, 3, 1.0, 0.0, cv::BORDER_REFLECT);
    cv::multiply(b.dx, b.dx, b.dx);
    cv::multiply(b.dy, b.dy, b.dy);
    cv::add(b.dx, b.dy, b.per_pixel);
  } else {
    cv::subtract(b.grey, cv::mean(b.grey)[0], b.per_pixel);
  }
  return b.per_pixel;
}

// The mean over window x window pixels: a separable filter of equal taps (OpenCV's vectorised row and column
// filters; boxFilter's running sum along the row is scalar and took as long as both Gaussian windows).
void BoxMean(const cv::Mat& src, int window, cv::Mat& dst) {
  const cv::Mat taps(window, 1, CV_32F, cv::Scalar(1.0 / window));
  cv::sepFilter2D(src, dst, CV_32F, taps, taps, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT);
}

// The focus measure over window x window pixels of rows k0..k1 of the band into `out` (k1 - k0 rows, the
// caller's memory). The band carries a margin of rows beyond the rows that are kept: the filters, given the kept
// rows as a sub-matrix, read their neighbours from the band (OpenCV looks outside a sub-matrix unless told
// BORDER_ISOLATED) and filter no row that is not kept; at the image's own edges they reflect. `gaussian`:
// weighted by a Gaussian of sigma 0.3 window instead of evenly (the adaptive mode's wall windows: the centre's
// own height weighs most, where a box mixes in the heights at its edge as much).
void WindowMeasure(const cv::Mat& pixel_measure, int k0, int k1, FocusMeasure measure, int window, bool gaussian,
                   Scratch& b, cv::Mat& out) {
  const cv::Mat kept = pixel_measure.rowRange(k0, k1);
  if (gaussian) {
    const int side = 2 * KernelHalfWidth(window, true) + 1;
    cv::GaussianBlur(kept, out, cv::Size(side, side), kGaussianWindowSigma * window, 0.0, cv::BORDER_REFLECT);
  } else {
    BoxMean(kept, window, out);
  }
  if (measure == FocusMeasure::kVariance) {
    cv::multiply(pixel_measure, pixel_measure, b.dx);
    BoxMean(b.dx.rowRange(k0, k1), window, b.mean_sq);
    cv::multiply(out, out, out);
    cv::subtract(b.mean_sq, out, out);
    cv::max(out, 0.0, out);
  }
}

// The measures m[0..count) of images first, first + 1, ... folded into one row of a window's curves, and the
// last two carried to the next batch. Per vector of pixels the state is loaded once, updated by every image of the
// batch in registers, and stored once: the same selects, in the same order, as folding the images one by one.
// GCC's vector extensions (GCC keeps the scalar loop's selects as branches), 8 pixels a vector, compiled twice:
// for AVX2 where the processor has it (blends, 8 lanes: the fold was a third of the reconstruction's time), and
// for the baseline instruction set (two SSE halves). Both give the same bits.
using Floats = float __attribute__((vector_size(32)));
using Ints = std::int32_t __attribute__((vector_size(32)));

__attribute__((target_clones("avx2", "default"))) void FoldBatch(WindowCurves& c, std::size_t row, int width,
                                                                  std::int32_t first, const float* const* m,
                                                                  int count) {
  float* __restrict best = c.best.data() + row;
  float* __restrict left2 = c.left2.data() + row;
  float* __restrict left = c.left.data() + row;
  float* __restrict right = c.right.data() + row;
  float* __restrict right2 = c.right2.data() + row;
  float* __restrict sum = c.sum.data() + row;
  float* __restrict floor = c.floor.data() + row;
  float* __restrict previous2 = c.previous2.data() + row;
  float* __restrict previous = c.previous.data() + row;
  std::int32_t* __restrict index = c.index.data() + row;
  constexpr int kLanes = int(sizeof(Floats) / sizeof(float));
  const Floats nan = Floats{} + kNoValue;
  int col = 0;
  for (; col + kLanes <= width; col += kLanes) {
    Floats b, l2, l1, r1, r2, s, f, p2, p1;
    Ints at;
    std::memcpy(&b, best + col, sizeof b), std::memcpy(&l2, left2 + col, sizeof l2);
    std::memcpy(&l1, left + col, sizeof l1), std::memcpy(&r1, right + col, sizeof r1);
    std::memcpy(&r2, right2 + col, sizeof r2), std::memcpy(&s, sum + col, sizeof s);
    std::memcpy(&f, floor + col, sizeof f), std::memcpy(&p2, previous2 + col, sizeof p2);
    std::memcpy(&p1, previous + col, sizeof p1), std::memcpy(&at, index + col, sizeof at);
    Ints k = Ints{} + first;
    for (int j = 0; j < count; ++j, k += 1) {
      Floats v;
      std::memcpy(&v, m[j] + col, sizeof v);
      const Ints better = v > b;  // false for NaN, as in the scalar loop
      const Ints at1 = at == k - 1, at2 = at == k - 2;
      b = better ? v : b;
      at = better ? k : at;
      l2 = better ? p2 : l2;
      l1 = better ? p1 : l1;
      r1 = better ? nan : (at1 ? v : r1);
      r2 = better ? nan : (at2 ? v : r2);
      s = s + v;
      f = f < v ? f : v;
      p2 = p1;
      p1 = v;
    }
    std::memcpy(best + col, &b, sizeof b), std::memcpy(left2 + col, &l2, sizeof l2);
    std::memcpy(left + col, &l1, sizeof l1), std::memcpy(right + col, &r1, sizeof r1);
    std::memcpy(right2 + col, &r2, sizeof r2), std::memcpy(sum + col, &s, sizeof s);
    std::memcpy(floor + col, &f, sizeof f), std::memcpy(previous2 + col, &p2, sizeof p2);
    std::memcpy(previous + col, &p1, sizeof p1), std::memcpy(index + col, &at, sizeof at);
  }
  for (; col < width; ++col) {
    float p2 = previous2[col], p1 = previous[col];
    for (int j = 0; j < count; ++j) {
      const std::int32_t k = first + j;
      const float v = m[j][col];
      const std::int32_t at = index[col];
      const bool better = v > best[col];
      if (at == k - 1) right[col] = v;
      if (at == k - 2) right2[col] = v;
      if (better) {
        best[col] = v, index[col] = k, left2[col] = p2, left[col] = p1;
        right[col] = right2[col] = kNoValue;
      }
      sum[col] += v;
      floor[col] = floor[col] < v ? floor[col] : v;
      p2 = p1, p1 = v;
    }
    previous2[col] = p2, previous[col] = p1;
  }
}

float PixelValue(const cv::Mat& image, int r, int col, int channel) {
  const int i = col * image.channels() + channel;
  switch (image.depth()) {
    case CV_8U:
      return image.ptr<std::uint8_t>(r)[i];
    case CV_16U:
      return image.ptr<std::uint16_t>(r)[i];
    default:
      return image.ptr<float>(r)[i];
  }
}

}  // namespace

template <typename T>
T* HugePageAllocator<T>::allocate(std::size_t n) {
  constexpr std::size_t kHugePage = std::size_t(2) << 20;
  const std::size_t bytes = std::max<std::size_t>(n * sizeof(T), 1);
  const bool huge = bytes >= kHugePage;
  const std::size_t rounded = huge ? (bytes + kHugePage - 1) / kHugePage * kHugePage : bytes;
  void* p = huge ? std::aligned_alloc(kHugePage, rounded) : std::malloc(rounded);
  if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  if (huge) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: without huge pages it runs as before
#endif
  return static_cast<T*>(p);
}
void AdviseHugePages(void* data, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHugePage = std::uintptr_t(2) << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHugePage - 1) / kHugePage * kHugePage;
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) / kHugePage * kHugePage;
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice only
#else
  (void)data, (void)bytes;
#endif
}

template struct HugePageAllocator<float>;
template struct HugePageAllocator<std::int32_t>;

void ForStripes(int rows, bool parallel, const std::function<void(int, int)>& body, int stripe_rows) {
  const int stripes = (rows + stripe_rows - 1) / stripe_rows;
  const auto run = [&](const cv::Range& range) {
    for (int s = range.start; s < range.end; ++s) body(s * stripe_rows, std::min(rows, (s + 1) * stripe_rows));
  };
  if (parallel) {
    cv::parallel_for_(cv::Range(0, stripes), run);
  } else {
    run(cv::Range(0, stripes));
  }
}

int BlurStripeRows(double sigma_px) {
  const int reach = int(std::ceil(8.0 * sigma_px));
  return std::max(kStripeRows, (reach + kStripeRows - 1) / kStripeRows * kStripeRows);
}

std::vector<float> WindowTaps(int window, bool gaussian) {
  if (!gaussian) return std::vector<float>(std::size_t(window), 1.0f / float(window));
  const cv::Mat taps =
      cv::getGaussianKernel(2 * KernelHalfWidth(window, true) + 1, kGaussianWindowSigma * window, CV_32F);
  return std::vector<float>(taps.begin<float>(), taps.end<float>());
}

void WindowCurves::Reset(int w, bool gaussian_window, std::size_t n) {
  window = w;
  gaussian = gaussian_window;
  for (auto* v : {&best, &left2, &left, &right, &right2, &sum, &floor, &previous2, &previous}) v->resize(n);
  index.resize(n);
}

void WindowCurves::Start(std::size_t begin, std::size_t end) {
  std::fill(best.begin() + begin, best.begin() + end, -std::numeric_limits<float>::infinity());
  for (auto* v : {&left2, &left, &right, &right2, &previous2, &previous}) {
    std::fill(v->begin() + begin, v->begin() + end, kNoValue);
  }
  std::fill(sum.begin() + begin, sum.begin() + end, 0.0f);
  std::fill(floor.begin() + begin, floor.begin() + end, std::numeric_limits<float>::max());
  std::fill(index.begin() + begin, index.begin() + end, 0);
}

void FocusCurves::Take(const StackImageView* grey, const StackImageView* texture_images, int count) {
  if (count == 0) return;
  std::vector<cv::Mat> images, textures;
  for (int j = 0; j < count; ++j) {
    images.push_back(WrapPixels(grey[j]));
    textures.push_back(WrapPixels(texture_images ? texture_images[j] : grey[j]));
  }
  // Derivative (1 px) plus the widest kernel's half-width: beyond that, a band's edge does not reach the rows it
  // keeps.
  int margin = 0;
  for (const WindowCurves& c : windows) margin = std::max(margin, KernelHalfWidth(c.window, c.gaussian) + 1);
  const std::size_t n_windows = windows.size();
  const int first = taken;
  ForStripes(height, parallel, [&](int r0, int r1) {
    const int b0 = std::max(0, r0 - margin), b1 = std::min(height, r1 + margin);
    const std::size_t plane = std::size_t(r1 - r0) * std::size_t(width);
    const std::size_t begin = std::size_t(r0) * std::size_t(width), end = std::size_t(r1) * std::size_t(width);
    if (first == 0) {
      for (WindowCurves& c : windows) c.Start(begin, end);
      const std::size_t channels = std::size_t(texture_channels);
      std::fill(texture.begin() + begin * channels, texture.begin() + end * channels, 0.0f);
    }
    Scratch& scratch = ThreadScratch();
    scratch.measures.resize(std::size_t(count) * n_windows * plane);
    const auto slot = [&](int j, std::size_t w) {
      return scratch.measures.data() + (std::size_t(j) * n_windows + w) * plane;
    };
    for (int j = 0; j < count; ++j) {
      const cv::Mat& per_pixel = PixelMeasure(images[std::size_t(j)], b0, b1, measure, scratch);
      for (std::size_t w = 0; w < n_windows; ++w) {
        cv::Mat out(r1 - r0, width, CV_32F, slot(j, w));
        WindowMeasure(per_pixel, r0 - b0, r1 - b0, measure, windows[w].window, windows[w].gaussian, scratch, out);
      }
    }
    const float* rows[kFocusBatch];
    for (int r = r0; r < r1; ++r) {
      const std::size_t row = std::size_t(r) * std::size_t(width), local = std::size_t(r - r0) * std::size_t(width);
      for (std::size_t w = 0; w < n_windows; ++w) {
        WindowCurves& c = windows[w];
        for (int j = 0; j < count; ++j) rows[j] = slot(j, w) + local;
        FoldBatch(c, row, width, first, rows, count);
        if (w != 0) continue;
        const std::size_t channels = std::size_t(texture_channels);
        for (int col = 0; col < width; ++col) {
          const int j = c.index[row + std::size_t(col)] - first;
          if (j < 0) continue;
          for (std::size_t ch = 0; ch < channels; ++ch) {
            texture[(row + std::size_t(col)) * channels + ch] = PixelValue(textures[std::size_t(j)], r, col, int(ch));
          }
        }
      }
    }
  });
  taken += count;
}

}  // namespace fvm::imaging
