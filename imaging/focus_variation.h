#pragma once
// Focus variation: a height map from a stack of images taken at known z positions. Each pixel's sharpness (the
// focus measure, over a small window) peaks in the image where the surface under it is in focus; the peak's z,
// interpolated between the images, is the height. The peak over the pixel's mean measure tells how much to
// trust it (the quality): texture-free or saturated spots have no clear peak and come out invalid.
//
// The stack is consumed one image at a time (FocusAccumulator), so that memory stays a few images whatever the
// stack's depth; ReconstructFocusStack does it for a stack held in memory.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imaging/focus_stack.h"
#include "imaging/height_map.h"

namespace fvm::imaging {

enum class FocusMeasure {
  kModifiedLaplacian,  // sum-modified-Laplacian [Nayar 1994]: |2I - I_left - I_right| + |2I - I_up - I_down|
  kTenengrad,          // Sobel gradient energy Gx^2 + Gy^2
  kVariance,           // grey-level variance
};

// "laplacian", "tenengrad", "variance".
std::string FocusMeasureName(FocusMeasure measure);
std::optional<FocusMeasure> ParseFocusMeasure(std::string_view name);

enum class PeakFit {
  // A parabola through the measure raised to -1/p, p the measure's blur exponent (below). Blurring a random
  // texture by a Gaussian of sigma s scales the measure as s^-p (p = 3 for the modified Laplacian, 4 for the
  // gradient energy, 2 for the variance), and the blur's variance grows as a parabola in the defocus
  // (s^2 = s0^2 + (k dz)^2, variances of the optics' and the texture's blur add), so the transformed focus curve is
  // a parabola and its vertex unbiased between images.
  kPower,
  kGaussian,   // a parabola through the log of the measure (exact for a Gaussian focus curve)
  kParabolic,  // a parabola through the measure itself
};

// The windows of the adaptive mode (px; Gaussian-weighted, sigma 0.3 window: 1.5 and 2.7 px for the heights): the large
// one wherever the heights it spans allow, the small one on steep walls. Once each window's height is moved to the
// centroid of its pixels' sharpness (focus_window_centroid.h), the large window's errors on a 24 deg wall are smaller
// than the small one's (0.08 against 0.11 step on the stacks of ../shared/bench/focusgen.py, 0.04 on either on this
// project's renderer): its noise is lower and the centroid takes up what its span of heights would bias. Windows
// smaller than 5 px leave the noise of a texture no sharper than the optics' diffraction floor (0.4-0.8 um in focus,
// about a pixel) several times the step's tenth.
// The 3 px window (sigma 0.9 px) gives no height: its best image per pixel makes the all-in-focus image, whose
// sharpness the larger windows would blur (focus-stack's own image on the real stack of focus_realdata_test.cc: 1.15
// times as sharp from the 3 px window, 1.06 from the 5 px one).
inline constexpr int kAdaptiveWindows[] = {3, 5, 9};

struct FocusVariationOptions {
  FocusMeasure measure = FocusMeasure::kModifiedLaplacian;
  int window = 5;  // odd, 3 to 51 px: the measure is summed (averaged) over window x window pixels
  // The window per pixel, from the local slope: a large window (9 px, Gaussian-weighted) averages the noise down
  // wherever the heights it spans allow (walls to about 30 deg at 1 um pixels and steps, once its height is moved
  // to the centroid of its pixels' sharpness); on steeper walls it mixes heights too far apart and the 5 px
  // window's height is taken. `window` is then unused.
  bool adaptive_window = true;
  PeakFit peak_fit = PeakFit::kPower;
  // Peak over mean measure below this: invalid. An unfocused pixel of pure noise has a peak of about 1.2-1.5
  // times its mean over a stack of ~30 images (the largest of N noisy samples); a textured surface in focus has
  // several times that.
  double min_quality = 2.0;
  // A peak on the first or last image: invalid (the surface may lie beyond the stack), or, when kept, the end
  // image's z with a step of uncertainty (for stacks that end on the nearest and farthest parts of the scene).
  bool keep_end_peaks = false;
  double dx_mm = 0.001;  // pixel size of the height map (the camera pixel on the object)
  double dy_mm = 0.0;    // 0: same as dx
  bool parallel = true;  // stripes of rows on OpenCV's thread pool; false: one thread (the benchmark's baseline)

  // Throws InputError for an even or out-of-range window, a non-positive pixel size, a negative quality.
  void Check() const;
};

struct FocusResult {
  HeightMap height;            // mm at the peak; NaN where the quality is too low or the peak is at either end
  // Standard uncertainty of each height (mm, same grid; NaN where the height is): the noise of the focus
  // curve propagated through the peak fit, and the spread of heights inside the window on a slope.
  std::vector<float> u_z_mm;
  std::vector<float> quality;  // peak over mean measure per pixel (row-major, same grid); 0 where flat
  std::vector<std::int32_t> peak_index;  // the image with the largest measure per pixel
  std::vector<float> window_px;  // the window each height comes from (px)
  // The all-in-focus image: each pixel as it is in the image where its neighbourhood is sharpest (the 3 px
  // window's peak), texture_channels values per pixel (1 grey or 3 colour, interleaved), in the images' scale.
  std::vector<float> texture;
  int texture_channels = 1;
  // The peak fit's phase-locked bias taken off the heights (focus_phase_bias.h): its rms over the phase (mm, 0 when
  // none was taken off) and, when none was, why.
  double phase_bias_rms_mm = 0.0;
  std::string phase_bias_declined;
  // The stack's typical focus curve on its gentle parts (MeasureCurveShape, focus_steep_curvature_bias.h): its
  // shoulder (the best image's neighbours over the peak) and shape ratio (about 4 for a round top, 2 for a V), 0
  // from too few peaks; and the shares (0 to 1) of the two corrections it gates: the slope taken from a sharp bend's
  // own side (narrow curves, focus_slope_beside_bends.h) and the steep walls' bias (narrow and V-topped curves).
  double curve_shoulder = 0.0, curve_shape_ratio = 0.0;
  double slope_beside_bends_share = 0.0;
  double steep_wall_bias_share = 0.0;
};

// Takes the images of a stack in order. Not thread-safe itself; it copies them into a batch of a few images and
// folds each batch into the curves in parallel stripes of rows (focus_stack_curves.h).
class FocusAccumulator {
 public:
  explicit FocusAccumulator(const FocusVariationOptions& options);
  ~FocusAccumulator();
  FocusAccumulator(const FocusAccumulator&) = delete;
  FocusAccumulator& operator=(const FocusAccumulator&) = delete;

  // Throws InputError (naming `name`, else the image's index) when the image is empty, differs in size from the
  // first one, is smaller than the window, or its z is not beyond the previous one in the stack's direction
  // (z must be strictly increasing or strictly decreasing: repeated or unsorted positions are refused).
  // `colour`, when given (same size, 1 or 3 channels), is what the all-in-focus image is made of; else the
  // grey image itself.
  void Add(const StackImageView& image, double z_mm, std::string_view name = {},
           const StackImageView* colour = nullptr);
  int count() const;

  // Throws InputError for a stack of fewer than 3 images (a peak needs a neighbour on either side).
  FocusResult Finish() const;

 private:
  friend FocusResult ReconstructFocusStack(const std::vector<StackImageView>&, const std::vector<double>&,
                                           const FocusVariationOptions&);
  struct State;
  std::unique_ptr<State> state_;
};

// The whole stack at once; z_mm[i] is the position of images[i]. Same errors as FocusAccumulator.
FocusResult ReconstructFocusStack(const std::vector<StackImageView>& images, const std::vector<double>& z_mm,
                                  const FocusVariationOptions& options);

}  // namespace fvm::imaging
