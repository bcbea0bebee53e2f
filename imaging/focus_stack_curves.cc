#include "imaging/focus_stack_curves.h"

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace fvm::imaging {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kGaussianWindowSigma = 0.3;  // per px of window: 0.9 px for 3, 1.5 px for 5

cv::Mat WrapPixels(const StackImage& image) {
  return std::visit(
      [&](const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        const int type = std::is_same_v<T, std::uint8_t> ? CV_8U : std::is_same_v<T, std::uint16_t> ? CV_16U : CV_32F;
        // OpenCV never writes through this header; it only lacks a const Mat type.
        return cv::Mat(image.height, image.width, CV_MAKETYPE(type, image.channels),
                       const_cast<void*>(static_cast<const void*>(v.data())));
      },
      image.pixels);
}

// Scratch images of one thread, kept from stripe to stripe and batch to batch: OpenCV reuses a Mat's memory when
// the size and type repeat, and allocating (and faulting in) fresh pages for every band cost a tenth of the time.
struct Scratch {
  cv::Mat grey, dx, dy, per_pixel, window, mean_sq;
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

// The measure per pixel of rows b0..b1 before it is averaged over a window: the modified Laplacian or the
// gradient energy; for the variance the grey levels themselves (shifted by the band's mean: E[I^2] - E[I]^2 in
// float loses everything to cancellation when the grey level is large against the contrast, as in 16-bit images).
const cv::Mat& PixelMeasure(const cv::Mat& image, int b0, int b1, FocusMeasure measure, Scratch& b) {
  if (measure == FocusMeasure::kModifiedLaplacian) {
    switch (image.depth()) {
      case CV_8U:
        ModifiedLaplacian<std::uint8_t>(image, b0, b1, b.per_pixel);
        break;
      case CV_16U:
        ModifiedLaplacian<std::uint16_t>(image, b0, b1, b.per_pixel);
        break;
      default:
        ModifiedLaplacian<float>(image, b0, b1, b.per_pixel);
        break;
    }
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

// The focus measure over window x window pixels (float, same size as the band). The band carries a margin of
// rows beyond the rows that are kept, so that the filters see real neighbours there; at the image's own edges
// they reflect. `gaussian`: weighted by a Gaussian of sigma 0.3 window instead of evenly (the adaptive mode's
// wall windows: the centre's own height weighs most, where a box mixes in the heights at its edge as much).
const cv::Mat& WindowMeasure(const cv::Mat& pixel_measure, FocusMeasure measure, int window, bool gaussian,
                             Scratch& b) {
  const cv::Size box(window, window);
  if (gaussian) {
    const int side = 2 * window + 1;  // +-3.3 sigma
    cv::GaussianBlur(pixel_measure, b.window, cv::Size(side, side), kGaussianWindowSigma * window, 0.0,
                     cv::BORDER_REFLECT);
  } else {
    cv::boxFilter(pixel_measure, b.window, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  }
  if (measure == FocusMeasure::kVariance) {
    cv::multiply(pixel_measure, pixel_measure, b.dx);
    cv::boxFilter(b.dx, b.mean_sq, CV_32F, box, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
    cv::multiply(b.window, b.window, b.window);
    cv::subtract(b.mean_sq, b.window, b.window);
    cv::max(b.window, 0.0, b.window);
  }
  return b.window;
}

// One image's measure `m` folded into one row of a window's curves; p1, p2: the measures of the two images before
// it. Branch-free (selects), so that it vectorises.
void FoldRow(WindowCurves& c, std::size_t row, int width, std::int32_t k, const float* __restrict m,
             const float* __restrict p1, const float* __restrict p2) {
  float* __restrict best = c.best.data() + row;
  float* __restrict left2 = c.left2.data() + row;
  float* __restrict left = c.left.data() + row;
  float* __restrict right = c.right.data() + row;
  float* __restrict right2 = c.right2.data() + row;
  float* __restrict sum = c.sum.data() + row;
  float* __restrict floor = c.floor.data() + row;
  std::int32_t* __restrict index = c.index.data() + row;
  int col = 0;
#if CV_SIMD
  // OpenCV's universal intrinsics: the selects below, a vector of pixels at a time (GCC does not vectorise the
  // scalar loop: it keeps the selects as branches).
  const cv::v_float32 nan = cv::vx_setall_f32(kNaN);
  const cv::v_int32 kv = cv::vx_setall_s32(k), k1 = cv::vx_setall_s32(k - 1), k2 = cv::vx_setall_s32(k - 2);
  constexpr int kLanes = cv::v_float32::nlanes;
  for (; col + kLanes <= width; col += kLanes) {
    const cv::v_float32 v = cv::vx_load(m + col), b = cv::vx_load(best + col);
    const cv::v_int32 at = cv::vx_load(index + col);
    const cv::v_float32 better = v > b;
    const cv::v_float32 at1 = cv::v_reinterpret_as_f32(at == k1), at2 = cv::v_reinterpret_as_f32(at == k2);
    cv::v_store(best + col, cv::v_select(better, v, b));
    cv::v_store(index + col, cv::v_select(cv::v_reinterpret_as_s32(better), kv, at));
    cv::v_store(left2 + col, cv::v_select(better, cv::vx_load(p2 + col), cv::vx_load(left2 + col)));
    cv::v_store(left + col, cv::v_select(better, cv::vx_load(p1 + col), cv::vx_load(left + col)));
    cv::v_store(right + col, cv::v_select(better, nan, cv::v_select(at1, v, cv::vx_load(right + col))));
    cv::v_store(right2 + col, cv::v_select(better, nan, cv::v_select(at2, v, cv::vx_load(right2 + col))));
    cv::v_store(sum + col, cv::vx_load(sum + col) + v);
    cv::v_store(floor + col, cv::v_min(cv::vx_load(floor + col), v));
  }
  cv::vx_cleanup();
#endif
  for (; col < width; ++col) {
    const float v = m[col];
    const std::int32_t at = index[col];
    const bool better = v > best[col];
    if (at == k - 1) right[col] = v;
    if (at == k - 2) right2[col] = v;
    if (better) {
      best[col] = v, index[col] = k, left2[col] = p2[col], left[col] = p1[col];
      right[col] = right2[col] = kNaN;
    }
    sum[col] += v;
    floor[col] = std::min(floor[col], v);
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

void ForStripes(int rows, bool parallel, const std::function<void(int, int)>& body) {
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

void WindowCurves::Reset(int w, bool gaussian_window, std::size_t n) {
  window = w;
  gaussian = gaussian_window;
  best.assign(n, -std::numeric_limits<float>::infinity());
  for (auto* v : {&left2, &left, &right, &right2, &previous2, &previous}) v->assign(n, kNaN);
  sum.assign(n, 0.0f);
  floor.assign(n, std::numeric_limits<float>::max());
  index.assign(n, 0);
}

void FocusCurves::Take(const StackImage* grey, const StackImage* texture_images, int count) {
  if (count == 0) return;
  std::vector<cv::Mat> images, textures;
  for (int j = 0; j < count; ++j) {
    images.push_back(WrapPixels(grey[j]));
    textures.push_back(WrapPixels(texture_images ? texture_images[j] : grey[j]));
  }
  // Derivative (1 px) plus the window's half-width (a Gaussian window's kernel reaches one window out): beyond
  // that, a band's edge does not reach the rows it keeps.
  int margin = 0;
  for (const WindowCurves& c : windows) margin = std::max(margin, (c.gaussian ? c.window : c.window / 2) + 1);
  const std::size_t n_windows = windows.size();
  const int first = taken;
  ForStripes(height, parallel, [&](int r0, int r1) {
    const int b0 = std::max(0, r0 - margin), b1 = std::min(height, r1 + margin);
    const std::size_t plane = std::size_t(r1 - r0) * std::size_t(width);
    Scratch& scratch = ThreadScratch();
    scratch.measures.resize(std::size_t(count) * n_windows * plane);
    const auto slot = [&](int j, std::size_t w) {
      return scratch.measures.data() + (std::size_t(j) * n_windows + w) * plane;
    };
    for (int j = 0; j < count; ++j) {
      const cv::Mat& per_pixel = PixelMeasure(images[std::size_t(j)], b0, b1, measure, scratch);
      for (std::size_t w = 0; w < n_windows; ++w) {
        const cv::Mat& m = WindowMeasure(per_pixel, measure, windows[w].window, windows[w].gaussian, scratch);
        for (int r = r0; r < r1; ++r)
          std::copy_n(m.ptr<float>(r - b0), width, slot(j, w) + std::size_t(r - r0) * std::size_t(width));
      }
    }
    for (int r = r0; r < r1; ++r) {
      const std::size_t row = std::size_t(r) * std::size_t(width), local = std::size_t(r - r0) * std::size_t(width);
      for (std::size_t w = 0; w < n_windows; ++w) {
        WindowCurves& c = windows[w];
        // The measure of image j of the batch, or (j < 0) of the images before it.
        const auto measure_row = [&](int j) -> float* {
          if (j == -1) return c.previous.data() + row;
          if (j == -2) return c.previous2.data() + row;
          return slot(j, w) + local;
        };
        for (int j = 0; j < count; ++j)
          FoldRow(c, row, width, first + j, measure_row(j), measure_row(j - 1), measure_row(j - 2));
        // Carry the last two measures to the next batch (previous2 first: with one image, it is the old previous).
        std::copy_n(measure_row(count - 2), width, c.previous2.data() + row);
        std::copy_n(measure_row(count - 1), width, c.previous.data() + row);
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
