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

Level Downsample(const Prepared& in, int scale) {
  const cv::Mat valid = in.valid.empty() ? cv::Mat::ones(in.value.size(), CV_32F) : in.valid;
  const cv::Mat value = in.valid.empty() ? in.value : in.value.mul(valid);
  Level out;
  if (scale > 1) {
    // Area averages over whole blocks: the level's pixel (i, j) is the full pixels [scale i, scale i + scale).
    const cv::Size size(in.value.cols / scale, in.value.rows / scale);
    const cv::Rect blocks(0, 0, size.width * scale, size.height * scale);
    cv::Mat weight;
    cv::resize(value(blocks), out.value, size, 0.0, 0.0, cv::INTER_AREA);
    cv::resize(valid(blocks), weight, size, 0.0, 0.0, cv::INTER_AREA);
    cv::threshold(weight, out.mask, 0.99, 1.0, cv::THRESH_BINARY);
    out.value = (out.value / cv::max(weight, 1e-6)).mul(out.mask);
  } else {
    out.value = value.clone();
    out.mask = valid.clone();
  }
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

int LandscapeScale(int cols, int rows) {
  int scale = 1;
  while (scale < 4 && std::min(cols, rows) / (2 * scale) >= 128) scale *= 2;
  return scale;
}

std::vector<LandscapePeak> OverlapNccPeaks(const Prepared& a, const Prepared& b, const Eigen::Vector2d& nominal,
                                           const Eigen::Vector2d& search, int scale, int min_pixels, int peaks) {
  const Level la = Downsample(a, scale), lb = Downsample(b, scale);
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
  cv::Mat ncc(y1 - y0 + 1, x1 - x0 + 1, CV_32F, cv::Scalar(kNone));
  for (int y = y0; y <= y1; ++y) {
    const int iy = (y % padded.height + padded.height) % padded.height;
    for (int x = x0; x <= x1; ++x) {
      const int ix = (x % padded.width + padded.width) % padded.width;
      const double count = std::round(n.at<float>(iy, ix));
      if (count < min_count) continue;
      const double ma = sa.at<float>(iy, ix) / count, mb = sb.at<float>(iy, ix) / count;
      const double va = saa.at<float>(iy, ix) / count - ma * ma, vb = sbb.at<float>(iy, ix) / count - mb * mb;
      // Variances at the float sums' rounding (a blank overlap) carry no correlation.
      const double floor = 1e-5 * std::max(saa.at<float>(iy, ix), sbb.at<float>(iy, ix)) / count;
      if (!(va > floor && vb > floor)) continue;
      ncc.at<float>(y - y0, x - x0) =
          static_cast<float>(std::clamp((sab.at<float>(iy, ix) / count - ma * mb) / std::sqrt(va * vb), -1.0, 1.0));
    }
  }
  cv::Mat dilated;
  cv::dilate(ncc, dilated, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(kNone));
  std::vector<LandscapePeak> out;
  for (int r = 0; r < ncc.rows; ++r) {
    for (int c = 0; c < ncc.cols; ++c) {
      const float v = ncc.at<float>(r, c);
      if (v <= kNone || v < dilated.at<float>(r, c)) continue;
      const int ix = ((c + x0) % padded.width + padded.width) % padded.width;
      const int iy = ((r + y0) % padded.height + padded.height) % padded.height;
      out.push_back({Eigen::Vector2i(c + x0, r + y0) * scale, v,
                     static_cast<int>(std::round(n.at<float>(iy, ix))) * scale * scale});
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // Plateaus give several equal maxima side by side: keep one per 3 x 3 neighbourhood.
  std::vector<LandscapePeak> kept;
  for (const auto& p : out) {
    const bool near = std::any_of(kept.begin(), kept.end(), [&](const LandscapePeak& k) {
      return (k.offset_px - p.offset_px).cwiseAbs().maxCoeff() <= scale;
    });
    if (!near) kept.push_back(p);
    if (static_cast<int>(kept.size()) >= peaks) break;
  }
  return kept;
}

}  // namespace fvm::imaging::detail
