#include "imaging/tile_pair_registration.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fvm::imaging {
namespace {

// Overlaps narrower than this give no usable correlation peak.
constexpr int kMinOverlapPx = 8;
// The floor of a pair's standard uncertainty per direction (MeasureAlignment).
constexpr double kSystematicPx = 0.005;

cv::Mat View(const TileImage& image) {
  // A read-only header on the Eigen buffer: OpenCV never writes through it.
  return cv::Mat(static_cast<int>(image.rows()), static_cast<int>(image.cols()), CV_32F,
                 const_cast<float*>(image.data()));
}

// A crop ready for matching: `value` high-passed, 0 where the tile had no valid pixel; `valid` 1 where it had
// one, 0 elsewhere (CV_32F), or empty when every pixel is valid. Focus-variation height maps leave steep flanks
// and dark spots invalid (NaN); intensity tiles have none.
struct Prepared {
  cv::Mat value;
  cv::Mat valid;
  int pad = 0;  // px of context around the overlap on every side (CropOverlap); interiors keep out of it
};

// A quadratic surface z = c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2 fitted to the valid pixels of the crop
// (every 4th each way) and subtracted: lens shading and a tilted part are smooth across a tile, and a quadratic
// takes them out whole.
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
  const Eigen::Matrix<double, 6, 1> c = normal.completeOrthogonalDecomposition().solve(rhs);
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
    cv::Mat values;
    crop.convertTo(values, CV_32F);
    const cv::Mat finite = values == values;
    if (cv::countNonZero(finite) == 0) return false;
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(values, &low, &high, nullptr, nullptr, finite);
    if (!(low >= 0.0 && high > 0.0)) return false;
  }
  return true;
}

// Where two tiles overlap when b's top-left corner sits at `whole`, both crops prepared; none when the overlap is
// narrower than kMinOverlapPx. Both crops are the overlap exactly, high-passed alike: a crop that reached into one
// tile's own pixels beyond the overlap low-passed other content than its partner's, and biased thin overlaps by a
// pixel. A thin overlap (narrow side below kThinOverlapPx) is then mirrored out by kThinPadPx on every side, both
// crops alike: refinement and quality keep 5-8 px from a crop's edges for the Lanczos taps, which left nothing of
// a 10-15 px overlap.
constexpr int kThinPadPx = 8;

struct Overlap {
  cv::Rect in_a, in_b;
  Prepared a, b;
};

void MirrorOut(Prepared& crop, int pad) {
  cv::copyMakeBorder(crop.value, crop.value, pad, pad, pad, pad, cv::BORDER_REFLECT);
  if (!crop.valid.empty()) cv::copyMakeBorder(crop.valid, crop.valid, pad, pad, pad, pad, cv::BORDER_REFLECT);
  crop.pad = pad;
}

std::optional<Overlap> CropOverlap(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole,
                                   double sigma, bool mirror_thin = true) {
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

// The normalised cross-correlation of two prepared crops of one size where b's pixel u meets a's pixel u + e,
// over the pixels valid in both; `pixels` counts them.
double OverlapNcc(const Prepared& a, const Prepared& b, const Eigen::Vector2i& e, int& pixels) {
  const int ux0 = std::max(0, -e.x()), ux1 = std::min(b.value.cols, a.value.cols - e.x());
  const int uy0 = std::max(0, -e.y()), uy1 = std::min(b.value.rows, a.value.rows - e.y());
  pixels = 0;
  if (ux1 - ux0 < kMinOverlapPx || uy1 - uy0 < kMinOverlapPx) return 0.0;
  const cv::Rect rb(ux0, uy0, ux1 - ux0, uy1 - uy0), ra = rb + cv::Point(e.x(), e.y());
  cv::Mat mask;
  if (!a.valid.empty() || !b.valid.empty()) {
    cv::Mat both = cv::Mat::ones(rb.size(), CV_32F);
    if (!a.valid.empty()) both = both.mul(a.valid(ra));
    if (!b.valid.empty()) both = both.mul(b.valid(rb));
    both.convertTo(mask, CV_8U);
  }
  pixels = mask.empty() ? rb.area() : cv::countNonZero(mask);
  if (pixels < kMinOverlapPx * kMinOverlapPx) return 0.0;
  cv::Scalar ma, sa, mb, sb;
  cv::meanStdDev(a.value(ra), ma, sa, mask);
  cv::meanStdDev(b.value(rb), mb, sb, mask);
  const double product = cv::mean(a.value(ra).mul(b.value(rb)), mask)[0];
  if (!(sa[0] > 0.0 && sb[0] > 0.0)) return 0.0;
  return (product - ma[0] * mb[0]) / (sa[0] * sb[0]);
}

// Candidate offsets of b in a's frame within `search` (per axis) of `nominal`: the nominal overlap widened by the
// window on every side is cut from each tile (a common size, clipped to the tiles), high-passed, and phase
// correlated; the `peaks` highest local maxima of the correlation surface, each with the wrap-around
// interpretations (a peak at p of a surface N wide is a shift of p or p - N) that fall in the window, are tested
// by the normalised cross-correlation of the overlap they imply. Best first.
std::vector<TranslationCandidate> SearchCandidates(const TileImage& a, const TileImage& b,
                                                   const Eigen::Vector2d& nominal, const Eigen::Vector2d& search,
                                                   int peaks, double sigma) {
  const Eigen::Vector2i n = nominal.array().round().cast<int>();
  const Eigen::Vector2i m = search.array().ceil().cast<int>();
  const cv::Rect frame_a(0, 0, static_cast<int>(a.cols()), static_cast<int>(a.rows()));
  const cv::Rect frame_b(n.x(), n.y(), static_cast<int>(b.cols()), static_cast<int>(b.rows()));  // in a's frame
  const cv::Rect overlap = frame_a & frame_b;
  const cv::Rect widened(overlap.x - m.x(), overlap.y - m.y(), overlap.width + 2 * m.x(), overlap.height + 2 * m.y());
  cv::Rect ra = widened & frame_a, rb = widened & frame_b;  // both in a's frame
  const cv::Size common(std::min(ra.width, rb.width), std::min(ra.height, rb.height));
  if (common.width < kMinOverlapPx || common.height < kMinOverlapPx) return {};
  // Trim the wider one on the side away from the overlap, so that the overlap stays whole in both.
  if (ra.width > common.width && ra.x < overlap.x) ra.x += ra.width - common.width;
  if (rb.width > common.width && rb.x < overlap.x) rb.x += rb.width - common.width;
  if (ra.height > common.height && ra.y < overlap.y) ra.y += ra.height - common.height;
  if (rb.height > common.height && rb.y < overlap.y) rb.y += rb.height - common.height;
  ra.width = rb.width = common.width;
  ra.height = rb.height = common.height;
  const bool logarithm = MatchingDomain(View(a)(ra), View(b)(rb - cv::Point(n.x(), n.y())));
  const Prepared pa = HighPass(View(a)(ra), sigma, logarithm);
  const Prepared pb = HighPass(View(b)(rb - cv::Point(n.x(), n.y())), sigma, logarithm);
  // Phase correlation: the inverse transform of the whitened cross-power spectrum, A's against B's conjugate,
  // peaks at e where B(u) = A(u + e). No window: the overlap lies at opposite edges of the two crops (a's right
  // part, b's left one), where any taper weighs it down, and unevenly, which moved the peaks of thin overlaps by
  // 2-3 px; the high-pass already leaves the crops' wrap-around edges little to correlate.
  cv::Mat fa, fb, cross, surface;
  cv::dft(pa.value, fa, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(pb.value, fb, cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(fa, fb, cross, 0, true);
  std::vector<cv::Mat> parts;
  cv::split(cross, parts);
  cv::Mat magnitude;
  cv::magnitude(parts[0], parts[1], magnitude);
  // Half-way whitening (the magnitude's square root): full whitening weighs every frequency alike, and in a sparse
  // overlap most of them hold only shot noise (the true peak of 5 x 5 tiles of blobs fell below the 8 highest);
  // none at all lets the brightest blobs and what is left of the background decide.
  cv::sqrt(magnitude, magnitude);
  magnitude += 1e-20;
  parts[0] /= magnitude;
  parts[1] /= magnitude;
  cv::merge(parts, cross);
  cv::idft(cross, surface, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  // Local maxima (3 x 3) of the periodic surface, highest first.
  cv::Mat wrapped, dilated;
  cv::copyMakeBorder(surface, wrapped, 1, 1, 1, 1, cv::BORDER_WRAP);
  cv::dilate(wrapped, dilated, cv::Mat::ones(3, 3, CV_8U));
  dilated = dilated(cv::Rect(1, 1, surface.cols, surface.rows));
  // Only where a shift lands in the window: along machining marks the surface is a ridge of maxima all along the
  // marks, and the highest ones anywhere on it left none in the window.
  const Eigen::Vector2i base(ra.x - rb.x + n.x(), ra.y - rb.y + n.y());  // the offset of a shift e = 0
  const auto in_window = [&](int p, int size, int axis) {
    for (const int e : {p, p - size}) {
      if (std::abs(base(axis) + e - nominal(axis)) <= search(axis)) return true;
    }
    return false;
  };
  std::vector<char> column_in(static_cast<size_t>(surface.cols)), row_in(static_cast<size_t>(surface.rows));
  for (int x = 0; x < surface.cols; ++x) column_in[static_cast<size_t>(x)] = in_window(x, surface.cols, 0);
  for (int y = 0; y < surface.rows; ++y) row_in[static_cast<size_t>(y)] = in_window(y, surface.rows, 1);
  std::vector<std::pair<float, cv::Point>> maxima;
  for (int y = 0; y < surface.rows; ++y) {
    if (!row_in[static_cast<size_t>(y)]) continue;
    const float* s = surface.ptr<float>(y);
    const float* d = dilated.ptr<float>(y);
    for (int x = 0; x < surface.cols; ++x) {
      if (column_in[static_cast<size_t>(x)] && s[x] >= d[x] && s[x] > 0.0f) maxima.emplace_back(s[x], cv::Point(x, y));
    }
  }
  const auto kept = std::min(maxima.size(), static_cast<size_t>(peaks));
  std::partial_sort(maxima.begin(), maxima.begin() + static_cast<std::ptrdiff_t>(kept), maxima.end(),
                    [](const auto& l, const auto& r) { return l.first > r.first; });
  maxima.resize(kept);
  std::vector<TranslationCandidate> out;
  for (const auto& [height, p] : maxima) {
    for (const int ex : {p.x, p.x - common.width}) {
      for (const int ey : {p.y, p.y - common.height}) {
        // b's pixel u of its crop is a's u + e of its crop: offset = rb.tl - ra.tl + e in a's frame, rb holding n.
        const Eigen::Vector2i e(ex, ey);
        const Eigen::Vector2i offset = base + e;
        if (((offset.cast<double>() - nominal).cwiseAbs() - search).maxCoeff() > 0.0) continue;
        const bool seen = std::any_of(out.begin(), out.end(), [&](const TranslationCandidate& c) {
          return c.offset_px == offset.cast<double>();
        });
        if (seen) continue;
        TranslationCandidate c;
        c.offset_px = offset.cast<double>();
        c.peak = height;
        c.ncc = OverlapNcc(pa, pb, e, c.overlap_px);
        if (c.overlap_px > 0) out.push_back(c);
      }
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // The correlation's peaks of broad blobs lie a pixel or two off the best overlap; the best one climbs the
  // normalised cross-correlation, a whole pixel at a time, within the window, to its local maximum. A step must
  // gain kNccTie: along machining marks the correlation is a ridge whose noise would lead the climb anywhere
  // along it.
  // (Climbing the best three instead moved no tile of sparse seeds 1-5 by more than 0.11 px, and none out of 0.5 px.)
  constexpr size_t kClimbed = 1;
  constexpr double kNccTie = 0.01;
  for (size_t k = 0; k < std::min(kClimbed, out.size()); ++k) {
    TranslationCandidate& c = out[k];
    Eigen::Vector2i offset = c.offset_px.cast<int>();
    for (int step = 0; step < 16; ++step) {
      TranslationCandidate best = c;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const Eigen::Vector2i next = offset + Eigen::Vector2i(dx, dy);
          if ((dx == 0 && dy == 0) || ((next.cast<double>() - nominal).cwiseAbs() - search).maxCoeff() > 0.0) continue;
          TranslationCandidate trial = c;
          trial.offset_px = next.cast<double>();
          trial.ncc = OverlapNcc(pa, pb, next - base, trial.overlap_px);
          if (trial.overlap_px > 0 && trial.ncc > best.ncc + kNccTie) best = trial;
        }
      }
      if (best.offset_px == c.offset_px) break;
      c = best;
      offset = c.offset_px.cast<int>();
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // Climbs that met keep the first.
  out.erase(std::unique(out.begin(), out.end(),
                        [](const auto& l, const auto& r) { return l.offset_px == r.offset_px; }),
            out.end());
  // Candidates within 2 kNccTie of the best match equally well as far as the overlap can tell (a ridge along
  // marks, a blank strip): the one nearest the nominal offset, in units of the window, goes first.
  if (!out.empty()) {
    const double floor = out.front().ncc - 2.0 * kNccTie;
    const auto distance = [&](const TranslationCandidate& c) {
      return (c.offset_px - nominal).cwiseQuotient(search.cwiseMax(1.0)).squaredNorm();
    };
    auto chosen = out.begin();
    for (auto it = out.begin(); it != out.end() && it->ncc >= floor; ++it) {
      if (distance(*it) < distance(*chosen)) chosen = it;
    }
    std::rotate(out.begin(), chosen, chosen + 1);
  }
  return out;
}

// Shift e such that B(v) = A(v + e), from the phase correlation of same-sized crops, and its peak response.
std::pair<Eigen::Vector2d, double> PhaseShift(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat window;
  cv::createHanningWindow(window, a.size(), CV_32F);
  double response = 0.0;
  // phaseCorrelate(a, b) returns t with b(x) = a(x - t).
  const cv::Point2d t = cv::phaseCorrelate(a, b, window, &response);
  return {Eigen::Vector2d(-t.x, -t.y), response};
}

// Lanczos-4: sinc(x) sinc(x / 4) for |x| < 4.
double Lanczos4(double x) {
  if (std::abs(x) < 1e-12) return 1.0;
  if (std::abs(x) >= 4.0) return 0.0;
  const double px = std::numbers::pi * x;
  return 4.0 * std::sin(px) * std::sin(px / 4.0) / (px * px);
}

// The 8 taps of Lanczos-4 interpolation at fraction f in [0, 1): weight j multiplies the sample at j - 3,
// normalised to sum 1 as OpenCV's INTER_LANCZOS4 does. Its pass band is flat to ~0.3 cycles / px, where bicubic
// interpolation already shifts the phase: with bicubic the refined shifts carried a bias of ~0.01-0.04 px that
// repeats at every pair with the same fraction, and so adds up along a row of tiles.
cv::Mat LanczosTaps(double f) {
  cv::Mat taps(1, 8, CV_32F);
  double sum = 0.0;
  for (int j = 0; j < 8; ++j) sum += Lanczos4(f - (j - 3));
  for (int j = 0; j < 8; ++j) taps.at<float>(0, j) = static_cast<float>(Lanczos4(f - (j - 3)) / sum);
  return taps;
}

// The gradient of an image as Lanczos-4 interpolates it, at the pixels: the derivative of the interpolation in
// the shift, sum_j L'(-k) I(v + k), k = j - 3. Refinement needs this one, not a finite difference: on texture that
// reaches the Nyquist frequency (the roughness of a face in a height map) a Sobel gradient overstates the step
// 2.7-fold and Gauss-Newton oscillates half a pixel off the match.
void InterpolationGradient(const cv::Mat& image, cv::Mat& gx, cv::Mat& gy) {
  static const cv::Mat derivative = [] {
    cv::Mat taps(1, 8, CV_32F);
    constexpr double h = 1e-5;
    for (int j = 0; j < 8; ++j) {
      const double k = j - 3;
      taps.at<float>(0, j) = static_cast<float>((Lanczos4(h - k) - Lanczos4(-h - k)) / (2 * h));
    }
    return taps;
  }();
  static const cv::Mat identity = (cv::Mat_<float>(1, 8) << 0, 0, 0, 1, 0, 0, 0, 0);
  cv::sepFilter2D(image, gx, CV_32F, derivative, identity, cv::Point(3, 3), 0.0, cv::BORDER_REFLECT);
  cv::sepFilter2D(image, gy, CV_32F, identity, derivative, cv::Point(3, 3), 0.0, cv::BORDER_REFLECT);
}

// A sampled at v + e for every v of `inner` (B's frame). A translation shifts every pixel by the same fraction,
// so the 8 x 8 Lanczos kernel is the product of two 8-tap filters: a separable filter of the window, 16
// multiply-adds a pixel instead of remap's 64. `inner` must keep 4 px of A around it after the shift.
cv::Mat ShiftedCrop(const cv::Mat& a, const Eigen::Vector2d& e, const cv::Rect& inner) {
  const int ix = static_cast<int>(std::floor(e.x())), iy = static_cast<int>(std::floor(e.y()));
  const cv::Rect window(inner.x + ix - 3, inner.y + iy - 3, inner.width + 7, inner.height + 7);
  cv::Mat filtered;
  cv::sepFilter2D(a(window), filtered, CV_32F, LanczosTaps(e.x() - ix), LanczosTaps(e.y() - iy), cv::Point(3, 3),
                  0.0, cv::BORDER_REFLECT);
  return filtered(cv::Rect(3, 3, inner.width, inner.height));
}

// B's interior: `margin` px in from every side, and never into the context around a thin overlap. ShiftedCrop
// reaches 3 px before and 4 px after a pixel, so a margin of 4 + ceil(|e|) keeps a shift by e inside A.
std::optional<cv::Rect> Interior(const Prepared& prepared, int margin) {
  const cv::Mat& b = prepared.value;
  margin = std::max(margin, prepared.pad);
  const cv::Rect inner(margin, margin, b.cols - 2 * margin, b.rows - 2 * margin);
  if (inner.width < kMinOverlapPx || inner.height < kMinOverlapPx) return std::nullopt;
  return inner;
}

// Where a pixel of `inner` counts: B valid there, and A valid wherever its resampling at v + e and the 8-tap
// gradients reach. Empty when both crops are whole.
cv::Mat Usable(const cv::Mat& a_valid, const cv::Mat& b_valid, const Eigen::Vector2d& e, const cv::Rect& inner) {
  if (a_valid.empty() && b_valid.empty()) return {};
  cv::Mat usable = cv::Mat::ones(inner.size(), CV_32F);
  if (!b_valid.empty()) usable = b_valid(inner).clone();
  if (!a_valid.empty()) {
    cv::Mat shifted;
    cv::threshold(ShiftedCrop(a_valid, e, inner), shifted, 0.999, 1.0, cv::THRESH_BINARY);
    usable = usable.mul(shifted);
  }
  cv::erode(usable, usable, cv::Mat::ones(9, 9, CV_8U));
  return usable;
}

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
                       Eigen::Vector2d* last_step = nullptr, Eigen::Vector2d* last_estimate = nullptr) {
  // Up to 4 px from the start: on a lay (marks in one direction) the correlation peak is a ridge, and its top
  // can lie a few pixels along it from the truth.
  constexpr double kWander = 4.0;
  constexpr int kIterations = 30;
  Eigen::Vector2d estimate = e;
  int iteration = 0;
  // The interior leaves room for the current shift and one pixel more; a step beyond it starts over with a
  // wider margin, so that a narrow overlap keeps most of its pixels while the shift stays small.
  while (iteration < kIterations) {
    const double reach = estimate.cwiseAbs().maxCoeff() + 1.0;
    const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(reach)));
    if (!inner) return Refinement::kNoRoom;
    // B's gradient, taken from B's own pixels around the interior.
    cv::Mat gx, gy;
    InterpolationGradient(b.value(*inner), gx, gy);
    const cv::Mat usable = Usable(a.valid, b.valid, estimate, *inner);
    if (!usable.empty()) {
      gx = gx.mul(usable);
      gy = gy.mul(usable);
    }
    const cv::Mat target = b.value(*inner);
    Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
    for (int y = 0; y < gx.rows; ++y) {
      const float* px = gx.ptr<float>(y);
      const float* py = gy.ptr<float>(y);
      for (int x = 0; x < gx.cols; ++x) {
        h(0, 0) += px[x] * px[x];
        h(0, 1) += px[x] * py[x];
        h(1, 1) += py[x] * py[x];
      }
    }
    h(1, 0) = h(0, 1);
    if (!(h.trace() > 0.0)) return Refinement::kNoTexture;
    // Damped by a hundredth of the largest gradient energy: along a direction without texture (machining marks)
    // the energy is the noise's, and undamped steps would follow the noise off the match; with texture the
    // damping only slows each step by 1 %.
    const Eigen::LDLT<Eigen::Matrix2d> solve(h + 0.01 * h.trace() * Eigen::Matrix2d::Identity());
    for (; iteration < kIterations; ++iteration) {
      const cv::Mat warped = ShiftedCrop(a.value, estimate, *inner);
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      for (int y = 0; y < gx.rows; ++y) {
        const float* px = gx.ptr<float>(y);
        const float* py = gy.ptr<float>(y);
        const float* w = warped.ptr<float>(y);
        const float* t = target.ptr<float>(y);
        for (int x = 0; x < gx.cols; ++x) {
          const double r = w[x] - t[x];
          g(0) += px[x] * r;
          g(1) += py[x] * r;
        }
      }
      // A(v + e) = B(v + d) with d = e - e_true; the step solves B(v + d) ~ B(v) + grad B . d for d.
      const Eigen::Vector2d step = solve.solve(g);
      estimate -= step;
      if (last_step != nullptr) *last_step = step;
      if (last_estimate != nullptr) *last_estimate = estimate;
      if ((estimate - e).norm() > kWander) return Refinement::kWandered;  // off the peak: not the same match
      if (step.norm() < tolerance_px) {
        e = estimate;
        return Refinement::kSettled;
      }
      if (estimate.cwiseAbs().maxCoeff() > reach) {
        ++iteration;
        break;  // beyond the interior's margin: again with a wider one
      }
    }
  }
  // Still moving by more than the tolerance: the estimate is not a minimum, and no precision can be claimed.
  return Refinement::kNotSettled;
}

// How well an aligned overlap matches, and how precisely it fixes the shift.
struct Alignment {
  double quality = 0.0;
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
};

Alignment MeasureAlignment(const Prepared& a, const Prepared& b, const Eigen::Vector2d& e) {
  Alignment out;
  const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(e.cwiseAbs().maxCoeff())));
  if (!inner) return out;
  const cv::Mat target = b.value(*inner);
  const cv::Mat warped = ShiftedCrop(a.value, e, *inner);
  const cv::Mat usable = Usable(a.valid, b.valid, e, *inner);
  // Gradients of both aligned crops.
  cv::Mat bx, by, ax, ay;
  InterpolationGradient(target, bx, by);
  InterpolationGradient(warped, ax, ay);
  // Sums per row in float (a row is at most a few thousand terms), over rows in double. The texture's gradient
  // energy comes from the cross products of A's and B's gradients: the two images' noise is independent, so it
  // adds nothing on average, where the energy of one image's gradients counts its noise too. The energies of A
  // and B alone scale the cross products' spread under pure noise. The quality is the normalised
  // cross-correlation of the values.
  Eigen::Matrix2d cross = Eigen::Matrix2d::Zero(), energy_a = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d energy_b = Eigen::Matrix2d::Zero();
  double n = 0.0, sw = 0.0, st = 0.0, sww = 0.0, stt = 0.0, swt = 0.0;
  for (int y = 0; y < bx.rows; ++y) {
    const float *pbx = bx.ptr<float>(y), *pby = by.ptr<float>(y), *pax = ax.ptr<float>(y), *pay = ay.ptr<float>(y);
    const float* w = warped.ptr<float>(y);
    const float* t = target.ptr<float>(y);
    const float* use = usable.empty() ? nullptr : usable.ptr<float>(y);
    float cxx = 0, cxy = 0, cyx = 0, cyy = 0, axx = 0, axy = 0, ayy = 0, bxx = 0, bxy = 0, byy = 0;
    float count = 0, rw = 0, rt = 0, rww = 0, rtt = 0, rwt = 0;
    for (int x = 0; x < bx.cols; ++x) {
      if (use != nullptr && use[x] == 0.0f) continue;
      cxx += pax[x] * pbx[x], cxy += pax[x] * pby[x], cyx += pay[x] * pbx[x], cyy += pay[x] * pby[x];
      axx += pax[x] * pax[x], axy += pax[x] * pay[x], ayy += pay[x] * pay[x];
      bxx += pbx[x] * pbx[x], bxy += pbx[x] * pby[x], byy += pby[x] * pby[x];
      count += 1, rw += w[x], rt += t[x], rww += w[x] * w[x], rtt += t[x] * t[x], rwt += w[x] * t[x];
    }
    // The cross products symmetrised: A's x gradient against B's y counts as much as the other way round.
    cross += (Eigen::Matrix2d() << cxx, 0.5 * (cxy + cyx), 0.5 * (cxy + cyx), cyy).finished();
    energy_a += (Eigen::Matrix2d() << axx, axy, axy, ayy).finished();
    energy_b += (Eigen::Matrix2d() << bxx, bxy, bxy, byy).finished();
    n += count, sw += rw, st += rt, sww += rww, stt += rtt, swt += rwt;
  }
  if (n < kMinOverlapPx * kMinOverlapPx) return out;
  const double var_w = sww / n - (sw / n) * (sw / n), var_t = stt / n - (st / n) * (st / n);
  const double covariance = swt / n - (sw / n) * (st / n);
  if (!(var_w > 0.0 && var_t > 0.0)) return out;
  out.quality = covariance / std::sqrt(var_w * var_t);
  // The residual's variance: mean of (w - t)^2.
  const double residual = (sww - 2.0 * swt + stt) / n;
  const double variance = std::max(residual, 1e-12 * energy_b.trace() / n);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> directions(cross);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d u = directions.eigenvectors().col(k);
    const double texture = directions.eigenvalues()(k);
    // Under noise alone the cross energy along u scatters by sqrt(E_a E_b / n); a direction counts at 8 of
    // those (the filters correlate neighbouring pixels, so n overstates the independent samples a few times).
    const double spread = std::sqrt(u.dot(energy_a * u) * u.dot(energy_b * u) / n);
    if (!(texture > 8.0 * spread)) continue;
    // Refinement settles where B's gradient, texture and noise, is orthogonal to the residual; so the shift's
    // variance along u is variance E_b / texture^2, B's gradient energy over the texture's squared (the
    // sandwich of Gauss-Newton with a noisy Jacobian). Below it lies what registration leaves when noise does not
    // dominate (Lanczos resampling of texture near 0.2 cycles / px, remnants of the shading): 0.005 px, the rms
    // error of noise-light synthetic pairs; without it the information overstated 512 px pairs 15-fold.
    const double noise_part = variance * u.dot(energy_b * u) / (texture * texture);
    out.information += 1.0 / (noise_part + kSystematicPx * kSystematicPx) * u * u.transpose();
  }
  return out;
}

}  // namespace

void RegistrationOptions::Check() const {
  if (!(min_quality >= -1.0 && min_quality <= 1.0)) throw std::invalid_argument("min_quality must be in [-1, 1]");
  if (!(max_correction > 0.0 && max_correction <= 0.5)) throw std::invalid_argument("max_correction: (0, 0.5]");
  if (!(search_fraction > 0.0 && search_fraction <= 0.5)) throw std::invalid_argument("search_fraction: (0, 0.5]");
  if (candidate_peaks < 1) throw std::invalid_argument("candidate_peaks must be >= 1");
  if (!(highpass_sigma_px >= 0.0)) throw std::invalid_argument("highpass_sigma_px must be >= 0");
  if (!(stage_sigma_px > 0.0)) throw std::invalid_argument("stage_sigma_px must be positive");
}

namespace {

// From a whole- or sub-pixel `offset` of b in a's frame: refines it on the overlap it implies, measures the
// quality and the information there, and decides. `searched`: the offset is a candidate of the widened search,
// which may lie a pixel or two off on broad blobs (the refinement may crop again, up to three times, and an
// offset it could not refine claims a pixel's variance less); otherwise it is the nominal overlap's
// phase-correlation peak, refined once on one crop (`reuse`, when given, is the crop at its whole pixel).
// Whole frames (cropped to a common size): the correlation finds the offset modulo the frame size; the
// representative nearest the nominal offset is taken. `response` gets the correlation peak.
Eigen::Vector2d WholeFrameShift(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                                double highpass_sigma_px, double& response) {
  const cv::Rect common(0, 0, static_cast<int>(std::min(a.cols(), b.cols())), static_cast<int>(std::min(a.rows(), b.rows())));
  const bool logarithm = MatchingDomain(View(a)(common), View(b)(common));
  const auto [e, peak] = PhaseShift(HighPass(View(a)(common), highpass_sigma_px, logarithm).value,
                                    HighPass(View(b)(common), highpass_sigma_px, logarithm).value);
  response = peak;
  Eigen::Vector2d offset = e;
  offset.x() += common.width * std::round((nominal_px.x() - e.x()) / common.width);
  offset.y() += common.height * std::round((nominal_px.y() - e.y()) / common.height);
  return offset;
}

void RefineAndMeasure(const TileImage& a, const TileImage& b, Eigen::Vector2d offset,
                      const RegistrationOptions& options, bool searched, std::optional<Overlap> reuse,
                      PairRegistration& pair) {
  const Eigen::Vector2d nominal_px = pair.nominal_px;
  const int crops = searched ? 3 : 1;
  // Crop again where the images really overlap, to the whole pixel: the shift left to refine is at most half a
  // pixel, so the refinement and the quality lose only a few pixels of a narrow overlap to their margins.
  // A refinement that ends more than half a pixel from its start crops again there and refines once more (a
  // candidate on broad blobs can be a pixel or two off): the shift left to refine stays below a pixel, where thin
  // overlaps keep their interior.
  Eigen::Vector2i whole;
  std::optional<Overlap> overlap;
  Eigen::Vector2d e;
  bool settled = !options.refine;  // the peak alone claims nothing more when asked for nothing more
  for (int crop = 0; crop < crops; ++crop) {
  whole = offset.array().round().cast<int>();
  overlap = crop == 0 && reuse ? std::move(reuse) : CropOverlap(a, b, whole, options.highpass_sigma_px);
  if (!overlap) {
    pair.rejection = "the measured overlap is narrower than 8 px";
    return;
  }
  e = offset - whole.cast<double>();
  if (options.refine) {
    // Coarse to fine: the phase-correlation peak can be a pixel off, outside the basin of Gauss-Newton on fine
    // texture (a quarter period); blurred crops widen the basin, then the full-resolution pass sets the sub-pixel.
    Eigen::Vector2d refined = e;
    // The coarse pass only needs to land in the fine pass' basin, so its not settling is no verdict (the fine pass
    // starts from the correlation's estimate then); the fine one stops well below the noise, and a fine pass
    // that runs out of iterations still moving rejects the pair: its shift is not a minimum of the mismatch.
    Eigen::Vector2d coarse = e;
    const Refinement coarse_status = RefineShift(Blur(overlap->a, 2.5), Blur(overlap->b, 2.5), 0.05, coarse);
    if (coarse_status == Refinement::kSettled) refined = coarse;
    Eigen::Vector2d last_step = Eigen::Vector2d::Zero(), last_estimate = refined;
    const Refinement fine = coarse_status == Refinement::kSettled || coarse_status == Refinement::kNotSettled
                                ? RefineShift(overlap->a, overlap->b, 2e-3, refined, &last_step, &last_estimate)
                                : coarse_status;
    settled = fine == Refinement::kSettled;
    if (fine == Refinement::kSettled) e = refined;
    if (fine == Refinement::kNotSettled) {
      // Out of iterations while still moving. The pair stands only if the last step is below half a standard
      // deviation of the offset it will claim (in the directions its texture determines: along machining marks
      // the steps follow the noise, and the information leaves that direction to the stage); otherwise the
      // offset is no minimum within its own precision, and the pair is rejected.
      const Alignment at = MeasureAlignment(overlap->a, overlap->b, last_estimate);
      const double moving = std::sqrt(last_step.dot(at.information * last_step));
      if (moving <= 0.5) {
        e = last_estimate;
        settled = true;
      } else {
        pair.rejection = "the sub-pixel refinement did not settle (its last step, " + std::to_string(last_step.norm()) +
                         " px, is " + std::to_string(moving) + " standard deviations of the offset)";
      }
    }
    // Otherwise (no room, no texture, wandered) the phase-correlation estimate stands, and the quality and the
    // texture test below decide.
  }
  offset = whole.cast<double>() + e;
  if (!pair.rejection.empty() || (offset.array().round().cast<int>() == whole.array()).all()) break;
  }
  const Alignment alignment = MeasureAlignment(overlap->a, overlap->b, e);
  pair.quality = alignment.quality;
  pair.information = alignment.information;
  if (searched && !settled && !pair.information.isZero()) {
    // Not refined (no room, wandered): the offset is a whole-pixel candidate, or the correlation's peak, which
    // on broad blobs lies up to a pixel off. Its information says what the overlap could tell, not what this
    // estimate holds: add a pixel's variance (0.5 px standard deviation) in every direction it claims.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> directions(pair.information);
    Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
    for (int k = 0; k < 2; ++k) {
      const double lambda = directions.eigenvalues()(k);
      const Eigen::Vector2d u = directions.eigenvectors().col(k);
      if (lambda > 1e-9 * directions.eigenvalues()(1)) information += 1.0 / (1.0 / lambda + 0.25) * u * u.transpose();
    }
    pair.information = information;
  }
  pair.offset_px = offset;
  {
    // Along a direction the overlap does not determine (machining marks), the offset is wherever the search ended
    // on the ridge, up to the window's width from the truth; the nominal says as much, and no tilt of the rank-one
    // information by noise can then carry a wild value into the solve.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> directions(pair.information);
    if (directions.eigenvalues()(1) > 0.0 && directions.eigenvalues()(0) <= 1e-9 * directions.eigenvalues()(1)) {
      const Eigen::Vector2d u = directions.eigenvectors().col(1);
      const Eigen::Vector2d projected = nominal_px + u * u.dot(pair.offset_px - nominal_px);
      pair.offset_px = projected;
    }
  }
  if (pair.rejection.empty() && !(pair.quality >= options.min_quality)) {
    pair.rejection = "quality " + std::to_string(pair.quality) + " is below min_quality " + std::to_string(options.min_quality);
  }
  if (pair.rejection.empty() && pair.information.isZero()) {
    pair.rejection = "the overlap has no texture that stands out of the noise in any direction";
  }
  pair.accepted = pair.rejection.empty();
}

}  // namespace

PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options) {
  options.Check();
  PairRegistration pair;
  pair.nominal_px = nominal_px;
  const Eigen::Vector2i nominal_whole = nominal_px.array().round().cast<int>();
  std::optional<Overlap> nominal = CropOverlap(a, b, nominal_whole, options.highpass_sigma_px, false);
  if (!nominal) {
    pair.rejection = "the nominal overlap is narrower than 8 px";
    return pair;
  }
  const double limit = options.max_correction * std::min(nominal->in_a.width, nominal->in_a.height);
  pair.search_px = Eigen::Vector2d::Constant(limit);
  const int nominal_area = nominal->in_a.area();

  Eigen::Vector2d offset;
  if (options.crop_to_overlap) {
    const auto [e, response] = PhaseShift(nominal->a.value, nominal->b.value);
    pair.response = response;
    offset = nominal_whole.cast<double>() + e;
  } else {
    offset = WholeFrameShift(a, b, nominal_px, options.highpass_sigma_px, pair.response);
  }
  if ((offset - nominal_px).cwiseAbs().maxCoeff() > limit) {
    pair.rejection = "the correlation's shift is farther from the nominal one than max_correction allows";
    return pair;
  }
  // The nominal crop serves again when the peak keeps its whole pixel and the overlap is not thin (a thin one is
  // cropped again, mirrored out for the refinement's margins).
  const bool thin = std::min(nominal->in_a.width, nominal->in_a.height) < kThinOverlapPx;
  std::optional<Overlap> reuse;
  if (!thin && offset.array().round().cast<int>().matrix() == nominal_whole) reuse = std::move(nominal);
  RefineAndMeasure(a, b, offset, options, false, std::move(reuse), pair);
  TranslationCandidate single;
  single.offset_px = pair.offset_px;
  single.peak = pair.response;
  single.ncc = pair.quality;
  single.overlap_px = nominal_area;
  pair.candidates.push_back(single);
  return pair;
}

PairRegistration SearchPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                            const Eigen::Vector2d& search_px, const RegistrationOptions& options) {
  options.Check();
  if (!(search_px.minCoeff() >= 0.0)) throw std::invalid_argument("SearchPair: the search window must be >= 0");
  PairRegistration pair;
  pair.nominal_px = nominal_px;
  pair.search_px = search_px;
  pair.searched = true;
  const Eigen::Vector2i nominal_whole = nominal_px.array().round().cast<int>();
  const cv::Rect nominal_overlap =
      cv::Rect(0, 0, static_cast<int>(a.cols()), static_cast<int>(a.rows())) &
      cv::Rect(nominal_whole.x(), nominal_whole.y(), static_cast<int>(b.cols()), static_cast<int>(b.rows()));
  if (nominal_overlap.width < kMinOverlapPx || nominal_overlap.height < kMinOverlapPx) {
    pair.rejection = "the nominal overlap is narrower than 8 px";
    return pair;
  }
  Eigen::Vector2d offset;
  if (options.crop_to_overlap) {
    pair.candidates =
        SearchCandidates(a, b, nominal_px, search_px, options.candidate_peaks, options.highpass_sigma_px);
    if (pair.candidates.empty()) {
      pair.rejection = "no correlation peak implies an overlap within the search window";
      return pair;
    }
    pair.response = pair.candidates.front().peak;
    offset = pair.candidates.front().offset_px;
  } else {
    offset = WholeFrameShift(a, b, nominal_px, options.highpass_sigma_px, pair.response);
    if (((offset - nominal_px).cwiseAbs() - search_px).maxCoeff() > 0.0) {
      pair.rejection = "the correlation's shift lies outside the search window";
      return pair;
    }
  }
  RefineAndMeasure(a, b, offset, options, true, std::nullopt, pair);
  return pair;
}

HeightStep OverlapHeightStep(const TileImage& a, const TileImage& b, const Eigen::Vector2d& offset_px) {
  // Pixel (x, y) of a is pixel (x - ox, y - oy) of b.
  double sum = 0.0, squares = 0.0;  // about the first difference, so that large heights lose no digits
  int n = 0;
  double first = NAN;
  for (Eigen::Index y = 0; y < a.rows(); ++y) {
    const double by = static_cast<double>(y) - offset_px.y();
    const double fy = std::floor(by);
    if (fy < 0.0 || fy + 1.0 >= static_cast<double>(b.rows())) continue;
    for (Eigen::Index x = 0; x < a.cols(); ++x) {
      const double bx = static_cast<double>(x) - offset_px.x();
      const double fx = std::floor(bx);
      if (fx < 0.0 || fx + 1.0 >= static_cast<double>(b.cols())) continue;
      const auto r = static_cast<Eigen::Index>(fy), c = static_cast<Eigen::Index>(fx);
      const double tx = bx - fx, ty = by - fy;
      const double v = (1 - ty) * ((1 - tx) * b(r, c) + tx * b(r, c + 1)) + ty * ((1 - tx) * b(r + 1, c) + tx * b(r + 1, c + 1));
      const double d = static_cast<double>(a(y, x)) - v;
      if (!std::isfinite(d)) continue;  // NaN: an invalid pixel on either side
      if (n == 0) first = d;
      sum += d - first;
      squares += (d - first) * (d - first);
      ++n;
    }
  }
  HeightStep step;
  step.pixels = n;
  if (n == 0) return step;
  const double mean_about_first = sum / n;
  step.mean = first + mean_about_first;
  step.variance = std::max(0.0, squares / n - mean_about_first * mean_about_first) / n;
  return step;
}

}  // namespace fvm::imaging
