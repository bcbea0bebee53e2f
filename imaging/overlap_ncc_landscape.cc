#include "imaging/overlap_ncc_landscape.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>
#include <opencv2/imgproc.hpp>

namespace fvm::imaging::detail {

namespace {

// A tile on the pyramid level: its values (mean 0 over the valid pixels, 0 elsewhere) and its mask (1 where every
// full-resolution pixel under a level pixel was valid, else 0).
struct Level {
  cv::Mat value, mask;
};

Level OnLevel(const Prepared& in) {
  Level out;
  out.mask = in.valid.empty() ? cv::Mat::ones(in.value.size(), CV_32F) : in.valid.clone();
  out.value = in.valid.empty() ? in.value.clone() : in.value.mul(in.valid);
  cv::Mat used;
  out.mask.convertTo(used, CV_8U);
  if (cv::countNonZero(used) > 0) {
    out.value -= cv::mean(out.value, used)[0];
    out.value = out.value.mul(out.mask);
  }
  return out;
}

// The real DFT (packed) of m zero-padded to `padded`.
cv::Mat Spectrum(const cv::Mat& m, const cv::Size& padded) {
  cv::Mat p = cv::Mat::zeros(padded, CV_32F);
  m.copyTo(p(cv::Rect(0, 0, m.cols, m.rows)));
  cv::dft(p, p, 0, m.rows);
  return p;
}

// c(s) = sum over x of f(x + s) g(x), at s modulo the padded size (no wrap-around: the padding holds both).
cv::Mat Correlate(const cv::Mat& spectrum_f, const cv::Mat& spectrum_g) {
  cv::Mat c;
  cv::mulSpectrums(spectrum_f, spectrum_g, c, 0, true);
  cv::idft(c, c, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  return c;
}

}  // namespace

cv::Mat AreaDownsample(const cv::Mat& tile, int scale) {
  if (scale <= 1) return tile;
  // Whole blocks: the level's pixel (i, j) averages the full pixels [scale i, scale i + scale) each way; a block
  // with a NaN is NaN (invalid).
  const cv::Size size(tile.cols / scale, tile.rows / scale);
  cv::Mat out;
  cv::resize(tile(cv::Rect(0, 0, size.width * scale, size.height * scale)), out, size, 0.0, 0.0, cv::INTER_AREA);
  return out;
}

int LandscapeScale(int cols, int rows) {
  int scale = 1;
  while (scale < 4 && std::min(cols, rows) / (2 * scale) >= 128) scale *= 2;
  return scale;
}

NccLandscape OverlapNccPeaks(const Prepared& a, const Prepared& b, const Eigen::Vector2d& nominal,
                             const Eigen::Vector2d& search, int scale, int min_pixels, int peaks) {
  const Level la = OnLevel(a), lb = OnLevel(b);
  if (la.value.empty() || lb.value.empty()) return {};
  const cv::Size padded(cv::getOptimalDFTSize(la.value.cols + lb.value.cols),
                        cv::getOptimalDFTSize(la.value.rows + lb.value.rows));
  // The six sums over the overlap at every offset s (b's pixel u on a's u + s), each a correlation of a's and b's
  // masked values, squares or masks [Padfield 2012, eq. 9-13].
  const cv::Mat a1 = Spectrum(la.value, padded), a2 = Spectrum(la.value.mul(la.value), padded);
  const cv::Mat am = Spectrum(la.mask, padded);
  const cv::Mat b1 = Spectrum(lb.value, padded), b2 = Spectrum(lb.value.mul(lb.value), padded);
  const cv::Mat bm = Spectrum(lb.mask, padded);
  const cv::Mat n = Correlate(am, bm), sa = Correlate(a1, bm), sb = Correlate(am, b1);
  const cv::Mat saa = Correlate(a2, bm), sbb = Correlate(am, b2), sab = Correlate(a1, b1);
  // The window on the level, and the offsets a level's overlap can hold at all.
  const int x0 = std::max(static_cast<int>(std::ceil((nominal.x() - search.x()) / scale)), 1 - lb.value.cols);
  const int x1 = std::min(static_cast<int>(std::floor((nominal.x() + search.x()) / scale)), la.value.cols - 1);
  const int y0 = std::max(static_cast<int>(std::ceil((nominal.y() - search.y()) / scale)), 1 - lb.value.rows);
  const int y1 = std::min(static_cast<int>(std::floor((nominal.y() + search.y()) / scale)), la.value.rows - 1);
  if (x1 < x0 || y1 < y0) return {};
  const double min_count = std::max(1.0, static_cast<double>(min_pixels) / (scale * scale));
  constexpr float kNone = -2.0f;
  // The NCC at a level offset (x, y) from the six sums; kNone where the overlap is too small or blank.
  const auto ncc_at = [&](int x, int y, double needed) {
    const int iy = (y % padded.height + padded.height) % padded.height;
    const int ix = (x % padded.width + padded.width) % padded.width;
    const double count = std::round(n.at<float>(iy, ix));
    if (count < needed) return kNone;
    const double ma = sa.at<float>(iy, ix) / count, mb = sb.at<float>(iy, ix) / count;
    const double va = saa.at<float>(iy, ix) / count - ma * ma, vb = sbb.at<float>(iy, ix) / count - mb * mb;
    // Variances at the float sums' rounding (a blank overlap) carry no correlation.
    const double floor = 1e-5 * std::max(saa.at<float>(iy, ix), sbb.at<float>(iy, ix)) / count;
    if (!(va > floor && vb > floor)) return kNone;
    return static_cast<float>(std::clamp((sab.at<float>(iy, ix) / count - ma * mb) / std::sqrt(va * vb), -1.0, 1.0));
  };
  NccLandscape out;
  out.unmoved_ncc = ncc_at(0, 0, 64.0);
  cv::Mat ncc(y1 - y0 + 1, x1 - x0 + 1, CV_32F, cv::Scalar(kNone));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) ncc.at<float>(y - y0, x - x0) = ncc_at(x, y, min_count);
  }
  cv::Mat dilated;
  cv::dilate(ncc, dilated, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(kNone));
  std::vector<LandscapePeak> found;
  for (int r = 0; r < ncc.rows; ++r) {
    for (int c = 0; c < ncc.cols; ++c) {
      const float v = ncc.at<float>(r, c);
      if (v <= kNone || v < dilated.at<float>(r, c)) continue;
      const int ix = ((c + x0) % padded.width + padded.width) % padded.width;
      const int iy = ((r + y0) % padded.height + padded.height) % padded.height;
      LandscapePeak peak{Eigen::Vector2i(c + x0, r + y0) * scale, v,
                         static_cast<int>(std::round(n.at<float>(iy, ix))) * scale * scale, 1.0};
      // How far it falls 4 level pixels away along each axis, at least (a ridge along marks: not at all).
      for (const auto& [dx, dy] : {std::pair{4, 0}, std::pair{-4, 0}, std::pair{0, 4}, std::pair{0, -4}}) {
        const float flank = ncc_at(c + x0 + dx, r + y0 + dy, min_count);
        if (flank > kNone) peak.fall = std::min(peak.fall, static_cast<double>(v - flank));
      }
      found.push_back(peak);
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // Plateaus give several equal maxima side by side: keep one per 3 x 3 neighbourhood.
  for (const auto& p : found) {
    const bool near = std::any_of(out.peaks.begin(), out.peaks.end(), [&](const LandscapePeak& k) {
      return (k.offset_px - p.offset_px).cwiseAbs().maxCoeff() <= scale;
    });
    if (!near) out.peaks.push_back(p);
    if (static_cast<int>(out.peaks.size()) >= peaks) break;
  }
  return out;
}

}  // namespace fvm::imaging::detail
