#include "imaging/translation_candidates.h"

#include "imaging/overlap_ncc_landscape.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <cmath>
#include <utility>
#include <vector>

namespace fvm::imaging::detail {

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

Prepared MatchingCrop(const cv::Mat& crop, const MatchScale& scale, bool logarithm) {
  const Prepared high = HighPass(crop, scale.highpass_sigma_px, logarithm);
  return scale.lowpass_sigma_px > 0.0 ? Blur(high, scale.lowpass_sigma_px) : high;
}

double MatchQuality(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole, const MatchScale& scale) {
  const std::optional<Overlap> overlap = CropOverlap(a, b, whole, scale.highpass_sigma_px, false);
  if (!overlap) return 0.0;
  int pixels = 0;
  if (scale.lowpass_sigma_px <= 0.0) return OverlapNcc(overlap->a, overlap->b, Eigen::Vector2i::Zero(), pixels);
  return OverlapNcc(Blur(overlap->a, scale.lowpass_sigma_px), Blur(overlap->b, scale.lowpass_sigma_px),
                    Eigen::Vector2i::Zero(), pixels);
}

namespace {

// A step of the narrow search's climb must gain this much: along machining marks the correlation is a ridge whose
// noise would lead the climb anywhere along it.
constexpr double kNccTie = 0.01;

// Climbs the normalised cross-correlation (`ncc_at(offset, pixels)`) a whole pixel at a time, within `search` of
// `nominal`, from c to its local maximum (16 steps at most); a step must gain kNccTie.
void ClimbNcc(TranslationCandidate& c, const Eigen::Vector2d& nominal, const Eigen::Vector2d& search,
              const std::function<double(const Eigen::Vector2i&, int&)>& ncc_at) {
  Eigen::Vector2i offset = c.offset_px.cast<int>();
  for (int step = 0; step < 16; ++step) {
    TranslationCandidate best = c;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Eigen::Vector2i next = offset + Eigen::Vector2i(dx, dy);
        if ((dx == 0 && dy == 0) || ((next.cast<double>() - nominal).cwiseAbs() - search).maxCoeff() > 0.0) continue;
        TranslationCandidate trial = c;
        trial.offset_px = next.cast<double>();
        trial.ncc = ncc_at(next, trial.overlap_px);
        if (trial.overlap_px > 0 && trial.ncc > best.ncc + kNccTie) best = trial;
      }
    }
    if (best.offset_px == c.offset_px) break;
    c = best;
    offset = c.offset_px.cast<int>();
  }
}

// Sorts candidates best first and puts first the one to take: among those that tie with the best, the nearest to
// `nominal`; when another place 3 px or more away matches within ambiguous_ncc (a repeating pattern), the nearest
// of those, and returns true (ambiguous).
bool ChooseAmongCandidates(std::vector<TranslationCandidate>& out, const Eigen::Vector2d& nominal,
                           const Eigen::Vector2d& search, double ambiguous_ncc) {
  std::stable_sort(out.begin(), out.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // Climbs that met keep the first.
  out.erase(std::unique(out.begin(), out.end(),
                        [](const auto& l, const auto& r) { return l.offset_px == r.offset_px; }),
            out.end());
  if (out.empty()) return false;
  // Candidates within 2 kNccTie of the best match equally well as far as the overlap can tell (a ridge along
  // marks, a blank strip): the one nearest the nominal offset, in units of the window, goes first.
  const double top = out.front().ncc;
  const auto distance = [&](const TranslationCandidate& c) {
    return (c.offset_px - nominal).cwiseQuotient(search.cwiseMax(1.0)).squaredNorm();
  };
  auto chosen = out.begin();
  for (auto it = out.begin(); it != out.end() && it->ncc >= top - 2.0 * kNccTie; ++it) {
    if (distance(*it) < distance(*chosen)) chosen = it;
  }
  std::rotate(out.begin(), chosen, chosen + 1);
  // Another place (3 px or more away) that matches within ambiguous_ncc of the best: a repeating pattern. The one
  // nearest the nominal offset (the stage's prediction) goes first, and the pair says it was a choice.
  bool ambiguous = false;
  auto nearest = out.begin();
  for (auto it = out.begin(); it != out.end(); ++it) {
    if (it->ncc < top - ambiguous_ncc) continue;
    if ((it->offset_px - out.front().offset_px).norm() >= 3.0) ambiguous = true;
    if (distance(*it) < distance(*nearest)) nearest = it;
  }
  if (ambiguous) std::rotate(out.begin(), nearest, nearest + 1);
  return ambiguous;
}

}  // namespace

// Candidate offsets of b in a's frame within `search` (per axis) of `nominal`: the nominal overlap widened by the
// window on every side is cut from each tile (a common size, clipped to the tiles), high-passed, and phase
// correlated; the `peaks` highest local maxima of the correlation surface, each with the wrap-around
// interpretations (a peak at p of a surface N wide is a shift of p or p - N) that fall in the window, are tested
// by the normalised cross-correlation of the overlap they imply. Best first.
std::vector<TranslationCandidate> SearchCandidates(const TileImage& a, const TileImage& b,
                                                   const Eigen::Vector2d& nominal, const Eigen::Vector2d& search,
                                                   int peaks, double sigma, const MatchScale& scale,
                                                   double ambiguous_ncc, bool& ambiguous) {
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
  // Candidates are judged on the crops with the pixel noise smoothed away (match_sigma): where the noise is as
  // strong as the texture at the finest scale (camera tiles of a printed grid), the correlation of the raw
  // high-pass told the true overlap from a wrong one by a few hundredths only.
  const Prepared sa = MatchingCrop(View(a)(ra), scale, logarithm);
  const Prepared sb = MatchingCrop(View(b)(rb - cv::Point(n.x(), n.y())), scale, logarithm);
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
        c.ncc = OverlapNcc(sa, sb, e, c.overlap_px);
        if (c.overlap_px > 0) out.push_back(c);
      }
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& l, const auto& r) { return l.ncc > r.ncc; });
  // The correlation's peaks of broad blobs lie a pixel or two off the best overlap; the best one climbs the
  // normalised cross-correlation within the window to its local maximum.
  // (Climbing the best three instead moved no tile of sparse seeds 1-5 by more than 0.11 px, and none out of 0.5 px.)
  if (!out.empty()) {
    ClimbNcc(out.front(), nominal, search, [&](const Eigen::Vector2i& offset, int& pixels) {
      return OverlapNcc(sa, sb, offset - base, pixels);
    });
  }
  ambiguous = ChooseAmongCandidates(out, nominal, search, ambiguous_ncc);
  return out;
}

WideSearch WideCandidates(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal,
                          const Eigen::Vector2d& search, int peaks, const MatchScale& scale, double ambiguous_ncc) {
  WideSearch out;
  out.scale = LandscapeScale(static_cast<int>(std::min(a.cols(), b.cols())), static_cast<int>(std::min(a.rows(), b.rows())));
  // Whole tiles on the level, in the matching band (its smoothing scaled to the level): each candidate is judged on
  // all of the overlap it implies.
  const bool logarithm = MatchingDomain(View(a), View(b));
  const MatchScale level{scale.highpass_sigma_px / out.scale, scale.lowpass_sigma_px / out.scale};
  const Prepared pa = MatchingCrop(AreaDownsample(View(a), out.scale), level, logarithm);
  const Prepared pb = MatchingCrop(AreaDownsample(View(b), out.scale), level, logarithm);
  // Offsets whose overlap is below a quarter of the nominal one are left out: a sliver correlates well by chance.
  const Eigen::Vector2i n = nominal.array().round().cast<int>();
  const cv::Rect overlap = cv::Rect(0, 0, static_cast<int>(a.cols()), static_cast<int>(a.rows())) &
                           cv::Rect(n.x(), n.y(), static_cast<int>(b.cols()), static_cast<int>(b.rows()));
  const int min_pixels = std::max(kMinOverlapPx * kMinOverlapPx, overlap.area() / 4);
  const NccLandscape landscape = OverlapNccPeaks(pa, pb, nominal, search, out.scale, min_pixels, peaks);
  out.unmoved_ncc = landscape.unmoved_ncc;
  for (const LandscapePeak& p : landscape.peaks) {
    TranslationCandidate c;
    c.offset_px = p.offset_px.cast<double>();
    c.peak = c.ncc = p.ncc;
    c.overlap_px = p.pixels;
    out.candidates.push_back(c);
  }
  // The sub-pixel refinement starts from the level's pixel (within half of it of the peak): no climb at full
  // resolution, which cost more than the landscape on the real strip.
  out.ambiguous = ChooseAmongCandidates(out.candidates, nominal, search, ambiguous_ncc);
  // Sharp: the chosen match falls by ambiguous_ncc 4 level pixels away along both axes (the real strip's peaks
  // are broad: 0.04-0.2 down 16 px away). Along machining marks it does not (a ridge of one maximum, whose place
  // along the marks is the noise's).
  if (!out.candidates.empty()) {
    const auto chosen = std::find_if(landscape.peaks.begin(), landscape.peaks.end(), [&](const LandscapePeak& p) {
      return p.offset_px.cast<double>() == out.candidates.front().offset_px;
    });
    out.sharp = chosen != landscape.peaks.end() && chosen->fall >= ambiguous_ncc;
  }
  return out;
}

Eigen::Vector2d PolishPeak(const TileImage& a, const TileImage& b, const Eigen::Vector2i& start, int radius,
                           const MatchScale& scale) {
  const bool logarithm = MatchingDomain(View(a), View(b));
  const Prepared pa = MatchingCrop(View(a), scale, logarithm), pb = MatchingCrop(View(b), scale, logarithm);
  // b's pixel u meets a's u + offset: OverlapNcc's e is the offset itself on whole tiles. Each offset once.
  std::map<std::pair<int, int>, double> seen;
  const auto ncc = [&](const Eigen::Vector2i& o) {
    const auto [it, fresh] = seen.try_emplace({o.x(), o.y()}, -2.0);
    int pixels = 0;
    if (fresh) it->second = OverlapNcc(pa, pb, o, pixels);
    if (fresh && pixels == 0) it->second = -2.0;
    return it->second;
  };
  // Uphill a pixel at a time within the radius (the peak lies within half a level's pixel of the start, so a few
  // steps: 20-30 overlaps where every offset of the radius would be 49-81).
  Eigen::Vector2i best = start;
  for (int step = 0; step <= 2 * radius; ++step) {
    Eigen::Vector2i next = best;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Eigen::Vector2i o = best + Eigen::Vector2i(dx, dy);
        if ((o - start).cwiseAbs().maxCoeff() <= radius && ncc(o) > ncc(next)) next = o;
      }
    }
    if (next == best) break;
    best = next;
  }
  // The vertex of the parabola through the best and its two neighbours, per axis; none where the three do not
  // bend down (a flat or rising side), and at most half a pixel away.
  const auto vertex = [&](const Eigen::Vector2i& along) {
    const double left = ncc(best - along), centre = ncc(best), right = ncc(best + along);
    const double bend = left - 2.0 * centre + right;
    if (!(bend < 0.0) || left < -1.5 || right < -1.5) return 0.0;
    return std::clamp(0.5 * (left - right) / bend, -0.5, 0.5);
  };
  return best.cast<double>() + Eigen::Vector2d(vertex(Eigen::Vector2i::UnitX()), vertex(Eigen::Vector2i::UnitY()));
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

}  // namespace fvm::imaging::detail
