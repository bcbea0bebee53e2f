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

namespace {

// The part of each level tile that some offset of the window [x0, x1] x [y0, y1] (b's pixel u on a's u + s)
// overlaps with the other: the rest takes part in no overlap the landscape looks at. A horizontal neighbour of a
// 10 % overlap searched a quarter of a tile either way reaches a third of each tile's width.
struct Reach {
  cv::Rect in_a, in_b;
};

Reach ReachOfWindow(const cv::Size& a, const cv::Size& b, int x0, int x1, int y0, int y1) {
  Reach r;
  r.in_a = cv::Rect(cv::Point(std::max(0, x0), std::max(0, y0)),
                    cv::Point(std::min(a.width, x1 + b.width), std::min(a.height, y1 + b.height)));
  r.in_b = cv::Rect(cv::Point(std::max(0, -x1), std::max(0, -y1)),
                    cv::Point(std::min(b.width, a.width - x0), std::min(b.height, a.height - y0)));
  return r;
}

// The six sums over the overlap at every offset s' of the crops (b's pixel u on a's u + s'), as correlations at
// s' modulo `padded` [Padfield 2012, eq. 9-13]: the count, a's and b's sums and sums of squares, and the cross sum.
struct OverlapSums {
  cv::Mat n, sa, sb, saa, sbb, sab;
};

OverlapSums SumsByTransforms(const Level& a, const Level& b, const cv::Size& padded) {
  const cv::Mat a1 = Spectrum(a.value, padded), a2 = Spectrum(a.value.mul(a.value), padded);
  const cv::Mat am = Spectrum(a.mask, padded);
  const cv::Mat b1 = Spectrum(b.value, padded), b2 = Spectrum(b.value.mul(b.value), padded);
  const cv::Mat bm = Spectrum(b.mask, padded);
  return {Correlate(am, bm), Correlate(a1, bm), Correlate(am, b1), Correlate(a2, bm), Correlate(am, b2),
          Correlate(a1, b1)};
}

// The same where every pixel of both crops is valid, at the offsets s' of `offsets` (x and y ranges, inclusive;
// elsewhere the count is 0): the count is the overlap's area, and the sums of each crop over it are box sums of
// its integral images; only the cross sum needs transforms (3 instead of 12).
OverlapSums SumsOfWholeCrops(const Level& a, const Level& b, const cv::Size& padded, const cv::Rect& offsets) {
  OverlapSums out;
  out.sab = Correlate(Spectrum(a.value, padded), Spectrum(b.value, padded));
  cv::Mat ia, iaa, ib, ibb;
  cv::integral(a.value, ia, iaa, CV_64F, CV_64F);
  cv::integral(b.value, ib, ibb, CV_64F, CV_64F);
  const auto box = [](const cv::Mat& integral, int x0, int y0, int x1, int y1) {
    return integral.at<double>(y1, x1) - integral.at<double>(y0, x1) - integral.at<double>(y1, x0) +
           integral.at<double>(y0, x0);
  };
  for (cv::Mat* m : {&out.n, &out.sa, &out.sb, &out.saa, &out.sbb}) *m = cv::Mat::zeros(padded, CV_32F);
  const int wa = a.value.cols, ha = a.value.rows, wb = b.value.cols, hb = b.value.rows;
  // Offsets with an overlap, s' in (-wb, wa) x (-hb, ha), each at its place modulo the padded size.
  for (int sy = std::max(1 - hb, offsets.y); sy < std::min(ha, offsets.y + offsets.height); ++sy) {
    const int ay0 = std::max(0, sy), ay1 = std::min(ha, hb + sy), by0 = ay0 - sy, by1 = ay1 - sy;
    const int iy = (sy % padded.height + padded.height) % padded.height;
    for (int sx = std::max(1 - wb, offsets.x); sx < std::min(wa, offsets.x + offsets.width); ++sx) {
      const int ax0 = std::max(0, sx), ax1 = std::min(wa, wb + sx), bx0 = ax0 - sx, bx1 = ax1 - sx;
      const int ix = (sx % padded.width + padded.width) % padded.width;
      out.n.at<float>(iy, ix) = static_cast<float>((ax1 - ax0) * (ay1 - ay0));
      out.sa.at<float>(iy, ix) = static_cast<float>(box(ia, ax0, ay0, ax1, ay1));
      out.saa.at<float>(iy, ix) = static_cast<float>(box(iaa, ax0, ay0, ax1, ay1));
      out.sb.at<float>(iy, ix) = static_cast<float>(box(ib, bx0, by0, bx1, by1));
      out.sbb.at<float>(iy, ix) = static_cast<float>(box(ibb, bx0, by0, bx1, by1));
    }
  }
  return out;
}

// The NCC of the level tiles one on the other (offset 0), -2 when blank or (with a mask) fewer than 64 pixels.
float UnmovedNcc(const Level& a, const Level& b) {
  double n = 0.0, sa = 0.0, sb = 0.0, saa = 0.0, sbb = 0.0, sab = 0.0;
  const int rows = std::min(a.value.rows, b.value.rows), cols = std::min(a.value.cols, b.value.cols);
  for (int y = 0; y < rows; ++y) {
    const float *va = a.value.ptr<float>(y), *vb = b.value.ptr<float>(y);
    const float *ma = a.mask.ptr<float>(y), *mb = b.mask.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      const double m = static_cast<double>(ma[x]) * mb[x];
      n += m, sa += m * va[x], sb += m * vb[x], saa += m * va[x] * va[x], sbb += m * vb[x] * vb[x];
      sab += m * va[x] * vb[x];
    }
  }
  n = std::round(n);
  if (n < 64.0) return -2.0f;
  const double ma = sa / n, mb = sb / n, va = saa / n - ma * ma, vb = sbb / n - mb * mb;
  const double floor = 1e-5 * std::max(saa, sbb) / n;
  if (!(va > floor && vb > floor)) return -2.0f;
  return static_cast<float>(std::clamp((sab / n - ma * mb) / std::sqrt(va * vb), -1.0, 1.0));
}

}  // namespace

NccLandscape OverlapNccPeaks(const Prepared& a, const Prepared& b, const Eigen::Vector2d& nominal,
                             const Eigen::Vector2d& search, int scale, int min_pixels, int peaks) {
  const Level whole_a = OnLevel(a), whole_b = OnLevel(b);
  if (whole_a.value.empty() || whole_b.value.empty()) return {};
  // The window on the level, and the offsets a level's overlap can hold at all.
  const cv::Size size_a = whole_a.value.size(), size_b = whole_b.value.size();
  const int x0 = std::max(static_cast<int>(std::ceil((nominal.x() - search.x()) / scale)), 1 - size_b.width);
  const int x1 = std::min(static_cast<int>(std::floor((nominal.x() + search.x()) / scale)), size_a.width - 1);
  const int y0 = std::max(static_cast<int>(std::ceil((nominal.y() - search.y()) / scale)), 1 - size_b.height);
  const int y1 = std::min(static_cast<int>(std::floor((nominal.y() + search.y()) / scale)), size_a.height - 1);
  if (x1 < x0 || y1 < y0) return {};
  NccLandscape out;
  out.unmoved_ncc = UnmovedNcc(whole_a, whole_b);
  // Only what the window's offsets (and the flanks 4 level pixels beyond them, that judge a peak's sharpness)
  // bring into an overlap is transformed: at s' = s + (b's crop corner) - (a's crop corner) the crops overlap as
  // the tiles do at s.
  constexpr int kFlank = 4;
  const cv::Rect looked_at(cv::Point(std::max(x0 - kFlank, 1 - size_b.width), std::max(y0 - kFlank, 1 - size_b.height)),
                           cv::Point(std::min(x1 + kFlank, size_a.width - 1) + 1,
                                     std::min(y1 + kFlank, size_a.height - 1) + 1));
  const Reach reach = ReachOfWindow(size_a, size_b, looked_at.x, looked_at.br().x - 1, looked_at.y, looked_at.br().y - 1);
  const Level la{whole_a.value(reach.in_a), whole_a.mask(reach.in_a)};
  const Level lb{whole_b.value(reach.in_b), whole_b.mask(reach.in_b)};
  const cv::Point shift = reach.in_b.tl() - reach.in_a.tl();
  const cv::Size padded(cv::getOptimalDFTSize(la.value.cols + lb.value.cols),
                        cv::getOptimalDFTSize(la.value.rows + lb.value.rows));
  const bool whole = a.valid.empty() && b.valid.empty();
  const OverlapSums sums =
      whole ? SumsOfWholeCrops(la, lb, padded, looked_at + shift) : SumsByTransforms(la, lb, padded);
  const cv::Mat &n = sums.n, &sa = sums.sa, &sb = sums.sb, &saa = sums.saa, &sbb = sums.sbb, &sab = sums.sab;
  const double min_count = std::max(1.0, static_cast<double>(min_pixels) / (scale * scale));
  constexpr float kNone = -2.0f;
  // The NCC at a level offset (x, y) from the six sums; kNone where the overlap is too small or blank, or the
  // crops do not reach it.
  const auto ncc_at = [&](int x, int y, double needed) {
    const int cx = x + shift.x, cy = y + shift.y;
    if (cx <= -lb.value.cols || cx >= la.value.cols || cy <= -lb.value.rows || cy >= la.value.rows) return kNone;
    const int iy = (cy % padded.height + padded.height) % padded.height;
    const int ix = (cx % padded.width + padded.width) % padded.width;
    const double count = std::round(n.at<float>(iy, ix));
    if (count < needed) return kNone;
    const double ma = sa.at<float>(iy, ix) / count, mb = sb.at<float>(iy, ix) / count;
    const double va = saa.at<float>(iy, ix) / count - ma * ma, vb = sbb.at<float>(iy, ix) / count - mb * mb;
    // Variances at the float sums' rounding (a blank overlap) carry no correlation.
    const double floor = 1e-5 * std::max(saa.at<float>(iy, ix), sbb.at<float>(iy, ix)) / count;
    if (!(va > floor && vb > floor)) return kNone;
    return static_cast<float>(std::clamp((sab.at<float>(iy, ix) / count - ma * mb) / std::sqrt(va * vb), -1.0, 1.0));
  };
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
      const int ix = ((c + x0 + shift.x) % padded.width + padded.width) % padded.width;
      const int iy = ((r + y0 + shift.y) % padded.height + padded.height) % padded.height;
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
