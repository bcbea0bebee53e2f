#include "imaging/overlap_correspondences.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>

namespace fvm::imaging {

void CorrespondenceOptions::Check() const {
  if (grid_step_px < 2 || window_px < 5 || window_px % 2 == 0 || pyramid_levels < 0 || pyramid_levels > 6 ||
      !(max_round_trip_px > 0.0) || !(highpass_sigma_px >= 0.0)) {
    throw std::invalid_argument(
        "correspondences: grid step >= 2 px, an odd window >= 5 px, 0-6 pyramid levels, round trip > 0");
  }
}

namespace {

// The tile high-passed (shading and offsets out) and stretched to 8 bits, as the tracker takes it: 128 +- 4 of the
// texture's standard deviations. Invalid pixels (NaN) read as the mean.
cv::Mat TrackableImage(const TileImage& tile, double sigma) {
  cv::Mat f(static_cast<int>(tile.rows()), static_cast<int>(tile.cols()), CV_32F);
  for (int y = 0; y < f.rows; ++y) {
    for (int x = 0; x < f.cols; ++x) f.at<float>(y, x) = tile(y, x);
  }
  const cv::Mat invalid = f != f;
  const double mean = cv::mean(f, ~invalid)[0];
  f.setTo(mean, invalid);
  if (sigma > 0.0) {
    cv::Mat low;
    cv::GaussianBlur(f, low, cv::Size(), sigma, sigma, cv::BORDER_REFLECT);
    f -= low;
  } else {
    f -= mean;
  }
  cv::Scalar m, sd;
  cv::meanStdDev(f, m, sd);
  const double scale = sd[0] > 0.0 ? 32.0 / sd[0] : 1.0;
  cv::Mat out;
  f.convertTo(out, CV_8U, scale, 128.0 - scale * m[0]);
  return out;
}

PairCorrespondences MatchPrepared(const cv::Mat& ia, const cv::Mat& ib, int a_index, int b_index,
                                  const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                  const CorrespondenceOptions& options) {
  PairCorrespondences out;
  out.a = a_index, out.b = b_index;
  const double half = options.window_px / 2 + 1.0;
  const double wa = ia.cols, ha = ia.rows, wb = ib.cols, hb = ib.rows;
  const double x0 = std::max(0.0, offset_px.x()) + half, x1 = std::min(wa, offset_px.x() + wb) - 1.0 - half;
  const double y0 = std::max(0.0, offset_px.y()) + half, y1 = std::min(ha, offset_px.y() + hb) - 1.0 - half;
  if (!(x1 > x0 && y1 > y0)) return out;
  const auto inside = [&](const cv::Point2f& p, double w, double h) {
    return p.x >= half && p.y >= half && p.x <= w - 1.0 - half && p.y <= h - 1.0 - half;
  };
  std::vector<cv::Point2f> from, to;
  // The grid centred in the overlap, so that its points sit symmetrically about the pair's middle.
  const int nx = static_cast<int>(std::floor((x1 - x0) / options.grid_step_px)) + 1;
  const int ny = static_cast<int>(std::floor((y1 - y0) / options.grid_step_px)) + 1;
  const double sx = 0.5 * ((x1 - x0) - (nx - 1) * options.grid_step_px);
  const double sy = 0.5 * ((y1 - y0) - (ny - 1) * options.grid_step_px);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Eigen::Vector2d ua(x0 + sx + i * options.grid_step_px, y0 + sy + j * options.grid_step_px);
      const Eigen::Vector2d ub = guess.RawPixel(ua + guess.Displacement(ua) - offset_px);
      const cv::Point2f pb(static_cast<float>(ub.x()), static_cast<float>(ub.y()));
      ++out.tried;
      if (!inside(pb, wb, hb)) continue;
      from.emplace_back(static_cast<float>(ua.x()), static_cast<float>(ua.y()));
      to.push_back(pb);
    }
  }
  if (from.empty()) return out;
  const cv::Size window(options.window_px, options.window_px);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-3);
  std::vector<unsigned char> status, back_status;
  std::vector<float> error, back_error;
  std::vector<cv::Point2f> back = from;
  cv::calcOpticalFlowPyrLK(ia, ib, from, to, status, error, window, options.pyramid_levels, stop,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  cv::calcOpticalFlowPyrLK(ib, ia, to, back, back_status, back_error, window, options.pyramid_levels, stop,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  for (size_t k = 0; k < from.size(); ++k) {
    if (!status[k] || !back_status[k] || !inside(to[k], wb, hb)) continue;
    const double dx = back[k].x - from[k].x, dy = back[k].y - from[k].y;
    if (std::hypot(dx, dy) > options.max_round_trip_px) continue;
    out.a_px.emplace_back(from[k].x, from[k].y);
    out.b_px.emplace_back(to[k].x, to[k].y);
  }
  return out;
}

}  // namespace

PairCorrespondences MatchOverlap(const TileImage& a, const TileImage& b, int a_index, int b_index,
                                 const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                 const CorrespondenceOptions& options) {
  options.Check();
  return MatchPrepared(TrackableImage(a, options.highpass_sigma_px), TrackableImage(b, options.highpass_sigma_px),
                       a_index, b_index, offset_px, guess, options);
}

std::vector<PairCorrespondences> MatchOverlaps(const std::vector<TileImage>& images,
                                               const std::vector<OverlapToMatch>& overlaps,
                                               const FieldDistortion& guess, const CorrespondenceOptions& options) {
  options.Check();
  for (const OverlapToMatch& o : overlaps) {
    if (o.a < 0 || o.b < 0 || o.a >= static_cast<int>(images.size()) || o.b >= static_cast<int>(images.size())) {
      throw std::invalid_argument("MatchOverlaps: a tile index outside the images");
    }
  }
  std::vector<cv::Mat> prepared(images.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(images.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      prepared[static_cast<size_t>(i)] = TrackableImage(images[static_cast<size_t>(i)], options.highpass_sigma_px);
    }
  });
  std::vector<PairCorrespondences> out(overlaps.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(overlaps.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const OverlapToMatch& o = overlaps[static_cast<size_t>(k)];
      out[static_cast<size_t>(k)] = MatchPrepared(prepared[static_cast<size_t>(o.a)], prepared[static_cast<size_t>(o.b)],
                                                  o.a, o.b, o.offset_px, guess, options);
    }
  });
  return out;
}

}  // namespace fvm::imaging
