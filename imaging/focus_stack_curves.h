#pragma once
// The focus curves of a stack, reduced as its images come (used by focus_variation.cc): per pixel and per
// window, the largest focus measure, its image, the measures of the two images on either side of it, the sum and
// the smallest over all images (mean and floor). Nothing else of the curve is kept, so memory stays a few images
// whatever the stack's depth.
//
// Speed: images are taken in batches of kFocusBatch. Per stripe of rows, the batch's measures are computed (one
// modified Laplacian per image, shared by the windows; each window's filter on the kept rows only) and each row's
// state is updated by all the batch's images, a vector of pixels at a time held in registers. Stripes run on
// OpenCV's thread pool.

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <new>
#include <utility>
#include <vector>

#include "imaging/focus_stack.h"
#include "imaging/focus_variation.h"

namespace fvm::imaging {

inline constexpr int kFocusBatch = 8;

// The modified Laplacian is taken of each image smoothed by a Gaussian of this sigma (px, 5 taps): a second
// difference of neighbouring pixels weighs the sensor's white noise most at the highest frequencies, where optics
// with a diffraction floor (a PSF of 0.3-0.8 um in focus, about a pixel) and a texture correlated over a pixel or
// more leave little signal. On the independent stacks of ../shared/bench/focusgen.py (same window and fit, no
// other change) it takes the flat's error from 0.064 to 0.055 step at the bench's optics, from 0.088 to 0.043 at
// NA 0.9 with a 0.3 um floor, and with a 2 px texture from 0.25-1.0 to 0.14-0.24. It widens the focus curve by
// the same Gaussian: the power law of PeakFit::kPower holds with s^2 + 0.25 px^2.
inline constexpr double kPrefilterSigmaPx = 0.5;
inline constexpr int kPrefilterHalfWidth = 2;

// Memory for the curves' arrays (hundreds of MB for a 4-megapixel stack) in 2 MB transparent huge pages where
// Linux allows them: faulting in 4 kB pages one by one cost a fifth of the reconstruction's time. resize()
// leaves new elements uninitialised (default-initialised), so that the first touch, which faults the pages in,
// happens where they are first written: in parallel stripes, not in one thread's fill.
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  T* allocate(std::size_t n);
  void deallocate(T* p, std::size_t) { std::free(p); }
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};
template <typename T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

// Reserves room for n elements in an ordinary vector (the result's maps) and advises huge pages over the whole
// 2 MB pages inside it, before anything touches them.
void AdviseHugePages(void* data, std::size_t bytes);
template <typename T>
void ReserveInHugePages(std::vector<T>& v, std::size_t n) {
  v.reserve(n);
  AdviseHugePages(v.data(), v.capacity() * sizeof(T));
}

// One window's reduced focus curves (row-major, one value per pixel each).
struct WindowCurves {
  int window = 5;
  bool gaussian = false;  // a Gaussian-weighted window (sigma 0.3 window) instead of a box
  HugeVector<float> best, left2, left, right, right2, sum, floor;
  HugeVector<std::int32_t> index;
  // The measures of the last two images taken (carried from one batch to the next).
  HugeVector<float> previous2, previous;

  // Sizes the arrays for n pixels without touching them; the first batch sets each stripe's start values
  // (Start) in parallel.
  void Reset(int w, bool gaussian_window, std::size_t n);
  // The start values of pixels [begin, end): no peak yet.
  void Start(std::size_t begin, std::size_t end);
};

struct FocusCurves {
  int width = 0, height = 0;
  FocusMeasure measure = FocusMeasure::kModifiedLaplacian;
  bool parallel = true;
  std::vector<WindowCurves> windows;
  // The all-in-focus pixels: each pixel's value in the first window's best image (texture_channels each).
  HugeVector<float> texture;
  int texture_channels = 1;
  int taken = 0;  // images folded into the curves

  // Folds `count` images (grey, and what the texture is made of: their colour, or null for the grey images
  // themselves) into the curves; the first is image number `taken`. count <= kFocusBatch.
  void Take(const StackImageView* grey, const StackImageView* texture_images, int count);
};

// The 1-D taps of a window's separable filter (the measure over the window is this filter along x, then y): a
// Gaussian of sigma 0.3 window to 2.5 sigma, or window equal taps; they sum to 1.
std::vector<float> WindowTaps(int window, bool gaussian);

// Rows per stripe. Fixed (not derived from the thread count) so that the parallel and the single-threaded run
// filter exactly the same bands and give the same bits.
inline constexpr int kStripeRows = 32;

// Calls body(first_row, end_row) for each stripe of `stripe_rows` rows, on OpenCV's thread pool when `parallel`.
void ForStripes(int rows, bool parallel, const std::function<void(int, int)>& body, int stripe_rows = kStripeRows);

// Rows per stripe for a Gaussian blur of `sigma_px` done stripe by stripe (each stripe a region of interest, whose
// filter reads the rows 4 sigma beyond it): at least 8 sigma, in whole kStripeRows, so that a stripe filters at most
// twice its own rows (stripes of 32 rows under a 14 px blur filtered 4.5 times theirs: a third of `fvm focus` on a
// 768 px, 60-image stack). The stripes do not change the result.
int BlurStripeRows(double sigma_px);

}  // namespace fvm::imaging
