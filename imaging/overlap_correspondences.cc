#include "imaging/overlap_correspondences.h"
#include "core/dense_decomposition.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <Eigen/LU>
#include <Eigen/QR>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <memory>
#include <stdexcept>

namespace fvm::imaging {

struct PreparedTileSet {
  // A tile as the matching takes it: high-passed (shading and offsets out) in float, with its gradient, for the
  // sub-pixel refinement; and stretched to 8 bits (128 +- 4 of the texture's standard deviations) for the tracker.
  struct Tile {
    cv::Mat u8, value, gx, gy;
    // The tracker's pyramid of u8 with its derivatives (cv::buildOpticalFlowPyramid), built once: the tracker
    // builds it on every call otherwise, for the whole tile, which cost more than the tracking.
    std::vector<cv::Mat> pyramid;
    int pyramid_window_px = 0, pyramid_levels = -1;
  };
  std::vector<Tile> tiles;
};

void CorrespondenceOptions::Check() const {
  if (grid_step_px < 2 || window_px < 5 || window_px % 2 == 0 || pyramid_levels < 0 || pyramid_levels > 6 ||
      !(max_round_trip_px > 0.0) || !(highpass_sigma_px >= 0.0)) {
    throw std::invalid_argument(
        "correspondences: grid step >= 2 px, an odd window >= 5 px, 0-6 pyramid levels, round trip > 0");
  }
}

namespace {

using TrackableTile = PreparedTileSet::Tile;

// The Gaussian (px) the refinement's copy of each tile is smoothed with (TrackableImage).
constexpr double kRefinementSmoothingPx = 1.0;


// The image less the least-squares polynomial of degree 4 in x and y (vignetting, uneven illumination), fitted on
// every 4th pixel: a window's mean and gain are taken out in the refinement, not a slope across it.
cv::Mat LessShading(const cv::Mat& f) {
  const auto basis = [&](double x, double y, Eigen::Ref<Eigen::RowVectorXd> row) {
    const double xp[5] = {1.0, x, x * x, x * x * x, x * x * x * x}, yp[5] = {1.0, y, y * y, y * y * y, y * y * y * y};
    int k = 0;
    for (int degree = 0; degree <= 4; ++degree) {
      for (int j = 0; j <= degree; ++j) row(k++) = xp[degree - j] * yp[j];
    }
  };
  const double sx = 2.0 / f.cols, sy = 2.0 / f.rows;
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> values;
  for (int y = 0; y < f.rows; y += 4) {
    for (int x = 0; x < f.cols; x += 4) {
      Eigen::RowVectorXd row(15);
      basis(x * sx - 1.0, y * sy - 1.0, row);
      rows.push_back(row), values.push_back(f.at<float>(y, x));
    }
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), 15);
  Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
  for (size_t i = 0; i < rows.size(); ++i) a.row(static_cast<Eigen::Index>(i)) = rows[i], b(static_cast<Eigen::Index>(i)) = values[i];
  const Eigen::VectorXd c =
      Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(a, "the shading polynomial of an overlap window").solve(b);
  // Evaluated row by row: on one row the quartic is a polynomial in x alone, its 5 coefficients from c and y's
  // powers (Horner across the row; the basis per pixel cost more than the rest of the tile's preparation).
  cv::Mat out(f.size(), CV_32F);
  for (int y = 0; y < f.rows; ++y) {
    const double yy = y * sy - 1.0;
    const double yp[5] = {1.0, yy, yy * yy, yy * yy * yy, yy * yy * yy * yy};
    std::array<double, 5> in_x{};  // coefficient of x^i on this row
    int k = 0;
    for (int degree = 0; degree <= 4; ++degree) {
      for (int j = 0; j <= degree; ++j) in_x[static_cast<size_t>(degree - j)] += c(k++) * yp[j];
    }
    const float* source = f.ptr<float>(y);
    float* target = out.ptr<float>(y);
    for (int x = 0; x < f.cols; ++x) {
      const double xx = x * sx - 1.0;
      const double shading = (((in_x[4] * xx + in_x[3]) * xx + in_x[2]) * xx + in_x[1]) * xx + in_x[0];
      target[x] = static_cast<float>(source[x] - shading);
    }
  }
  return out;
}

// Invalid pixels (NaN) read as the mean.
TrackableTile TrackableImage(const TileImage& tile, double sigma) {
  cv::Mat f(static_cast<int>(tile.rows()), static_cast<int>(tile.cols()), CV_32F);
  for (int y = 0; y < f.rows; ++y) {
    for (int x = 0; x < f.cols; ++x) f.at<float>(y, x) = tile(y, x);
  }
  const cv::Mat invalid = f != f;
  const double mean = cv::mean(f, ~invalid)[0];
  f.setTo(mean, invalid);
  TrackableTile out;
  // The refinement's copy: the values less the shading's quartic over the whole tile, smoothed (sigma 1 px, the
  // same for both tiles: no shift); not high-passed, since a high-pass reflects the tile at its edges, where the
  // overlaps are, and so shifts what it shows there. Interpolation errs most near the Nyquist frequency, at the
  // fraction every point of a regular scan shares: smoothed, that error would not pass for field.
  cv::GaussianBlur(LessShading(f), out.value, cv::Size(), kRefinementSmoothingPx, kRefinementSmoothingPx,
                   cv::BORDER_REFLECT);
  cv::Sobel(out.value, out.gx, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REFLECT);  // central differences
  cv::Sobel(out.value, out.gy, CV_32F, 0, 1, 1, 0.5, 0.0, cv::BORDER_REFLECT);
  if (sigma > 0.0) {
    // The low-pass at a quarter of the resolution, brought back bilinearly: it is smooth on the scale of 4 px,
    // and the full-resolution blur of sigma 8 px (a 65-tap kernel) cost more than the rest of the tile's
    // preparation. Each pyrDown blurs by 1 px of its own input (variance 1, 4 px^2 at full resolution: (f^2 - 1)
    // / 3 after halving to 1 / f); the Gaussian at the reduced scale adds the rest. It only steadies the tracker's
    // start; each point is refined on `value`.
    cv::Mat low = f;
    int factor = 1;
    while (factor < 4 && sigma / (2 * factor) >= 1.0 && low.cols >= 64 && low.rows >= 64) {
      cv::pyrDown(low, low, cv::Size(), cv::BORDER_REFLECT);
      factor *= 2;
    }
    const double done = (factor * factor - 1) / 3.0;  // full-resolution variance of the halvings
    const double reduced = std::sqrt(std::max(sigma * sigma - done, 0.25)) / factor;
    cv::GaussianBlur(low, low, cv::Size(), reduced, reduced, cv::BORDER_REFLECT);
    if (factor > 1) cv::resize(low, low, f.size(), 0.0, 0.0, cv::INTER_LINEAR);
    f -= low;
  } else {
    f -= mean;
  }
  cv::Scalar m, sd;
  cv::meanStdDev(f, m, sd);
  const double scale = sd[0] > 0.0 ? 32.0 / sd[0] : 1.0;
  f.convertTo(out.u8, CV_8U, scale, 128.0 - scale * m[0]);
  return out;
}

// Keys' cubic convolution weights (a = -0.5) of the samples at -1, 0, 1, 2 for a point `f` past sample 0.
std::array<double, 4> CubicWeights(double f) {
  const auto w = [](double t) {
    t = std::abs(t);
    return t <= 1.0 ? (1.5 * t - 2.5) * t * t + 1.0 : ((-0.5 * t + 2.5) * t - 4.0) * t + 2.0;
  };
  return {w(1.0 + f), w(f), w(1.0 - f), w(2.0 - f)};
}

// The n x n patch of `image` whose first sample lies at `corner` (any sub-pixel point): one fraction for the whole
// patch, so the cubic is two separable passes. (cv::remap rounds a fraction to 1/32 px: too coarse to settle on.)
// False when the patch and its cubic's reach do not fit in the image.
bool CubicPatch(const cv::Mat& image, const Eigen::Vector2d& corner, int n, cv::Mat& patch) {
  const int ix = static_cast<int>(std::floor(corner.x())), iy = static_cast<int>(std::floor(corner.y()));
  if (ix < 1 || iy < 1 || ix + n + 2 > image.cols || iy + n + 2 > image.rows) return false;
  const std::array<double, 4> wx = CubicWeights(corner.x() - ix), wy = CubicWeights(corner.y() - iy);
  cv::Mat rows(n + 3, n, CV_64F);
  for (int r = 0; r < n + 3; ++r) {
    const float* line = image.ptr<float>(iy - 1 + r);
    for (int x = 0; x < n; ++x) {
      const float* at = line + ix + x - 1;
      rows.at<double>(r, x) = wx[0] * at[0] + wx[1] * at[1] + wx[2] * at[2] + wx[3] * at[3];
    }
  }
  patch.create(n, n, CV_64F);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      patch.at<double>(y, x) = wy[0] * rows.at<double>(y, x) + wy[1] * rows.at<double>(y + 1, x) +
                               wy[2] * rows.at<double>(y + 2, x) + wy[3] * rows.at<double>(y + 3, x);
    }
  }
  return true;
}

// The n x n patch of `image` at centre + J v for the window's offsets v (-h..h each way, n = 2h + 1): b's view of a's
// window when the two views differ by the linear map J (bicubic per sample). False when a sample's cubic reach leaves
// the image.
bool CubicWarpedPatch(const cv::Mat& image, const Eigen::Vector2d& centre, const Eigen::Matrix2d& j, int n,
                      cv::Mat& patch) {
  const int h = n / 2;
  patch.create(n, n, CV_64F);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const Eigen::Vector2d at = centre + j * Eigen::Vector2d(x - h, y - h);
      const int ix = static_cast<int>(std::floor(at.x())), iy = static_cast<int>(std::floor(at.y()));
      if (ix < 1 || iy < 1 || ix + 3 > image.cols || iy + 3 > image.rows) return false;
      const std::array<double, 4> wx = CubicWeights(at.x() - ix), wy = CubicWeights(at.y() - iy);
      double sum = 0.0;
      for (int r = 0; r < 4; ++r) {
        const float* line = image.ptr<float>(iy - 1 + r) + ix - 1;
        sum += wy[static_cast<size_t>(r)] * (wx[0] * line[0] + wx[1] * line[1] + wx[2] * line[2] + wx[3] * line[3]);
      }
      patch.at<double>(y, x) = sum;
    }
  }
  return true;
}

// The tracker interpolates bilinearly, which pulls a sub-pixel shift towards whole pixels by up to a few
// hundredths of a pixel on fine speckle, the same way at every point of a regular scan (whose steps share their
// fraction): a bias that would pass for field. So each point is refined by inverse-compositional Gauss-Newton
// on sum (B(e + v) - A(u_a + v))^2 over the window (Baker, Matthews 2004), B resampled bicubically: A's template
// at whole pixels, its gradient computed once. Returns false when the refinement does not settle.
//
// `j` maps an offset in a's window to b's (the field's Jacobians at both ends, WindowMap): a field stretches the two
// views of one point differently (by 2 % across a 20 % band of 512 px tiles at 3 px of radial field), and a
// translation fitted to windows that differ by a stretch varying across the band is biased at second order in it,
// the same way in every overlap: on scangen's scans with the true field as the guess, the own-axis cubic the
// correspondences implied was off by about 0.0017 D^2 px (0.015 px at D = 3), 3-5 times its noise. With b's window
// warped by the guess's map, the translation is fitted to views that agree to the guess's error.
bool RefinePoint(const TrackableTile& a, const TrackableTile& b, const cv::Point& ua, int half,
                 const Eigen::Matrix2d& j, Eigen::Vector2d& e) {
  const bool warped = !j.isIdentity(0.0);
  const int n = 2 * half + 1;
  const cv::Rect box(ua.x - half, ua.y - half, n, n);
  if ((box & cv::Rect(0, 0, a.value.cols, a.value.rows)) != box) return false;
  const cv::Mat t = a.value(box), gx = a.gx(box), gy = a.gy(box);
  // Each window about its own mean and scaled to a's spread: shading and gain differ from tile to tile.
  cv::Scalar t_mean, t_sd;
  cv::meanStdDev(t, t_mean, t_sd);
  Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const Eigen::Vector2d g(gx.at<float>(y, x), gy.at<float>(y, x));
      h += g * g.transpose();
    }
  }
  if (!(h.determinant() > 1e-12 * h.trace() * h.trace())) return false;
  const Eigen::Matrix2d h_inverse = h.inverse();
  cv::Mat sampled;
  for (int iteration = 0; iteration < 10; ++iteration) {
    if (warped ? !CubicWarpedPatch(b.value, e, j, n, sampled)
               : !CubicPatch(b.value, e - Eigen::Vector2d::Constant(half), n, sampled)) {
      return false;
    }
    cv::Scalar s_mean, s_sd;
    cv::meanStdDev(sampled, s_mean, s_sd);
    if (!(s_sd[0] > 0.0)) return false;
    const double gain = t_sd[0] / s_sd[0];
    Eigen::Vector2d r = Eigen::Vector2d::Zero();
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const double d = gain * (sampled.at<double>(y, x) - s_mean[0]) - (t.at<float>(y, x) - t_mean[0]);
        r += d * Eigen::Vector2d(gx.at<float>(y, x), gy.at<float>(y, x));
      }
    }
    const Eigen::Vector2d step = j * (h_inverse * r);  // a's translation, seen in b
    e -= step;
    if (step.norm() < 1e-3) return true;
    if (step.norm() > 2.0) return false;
  }
  return false;
}

// How an offset about a's pixel maps to b's view of the same point under the field: (I + grad d(u_b))^-1 (I + grad
// d(u_a)), the field's Jacobians by central differences (a polynomial of low order: exact to 1e-6). The identity for
// the identity field.
Eigen::Matrix2d WindowMap(const FieldDistortion& field, const Eigen::Vector2d& ua, const Eigen::Vector2d& ub) {
  if (field.Identity()) return Eigen::Matrix2d::Identity();
  const auto jacobian = [&](const Eigen::Vector2d& u) {
    Eigen::Matrix2d g = Eigen::Matrix2d::Identity();
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d step = Eigen::Vector2d::Unit(k);
      g.col(k) += 0.5 * (field.Displacement(u + step) - field.Displacement(u - step));
    }
    return g;
  };
  return jacobian(ub).inverse() * jacobian(ua);
}

PairCorrespondences MatchPrepared(const TrackableTile& ta, const TrackableTile& tb, int a_index, int b_index,
                                  const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                  const CorrespondenceOptions& options) {
  PairCorrespondences out;
  out.a = a_index, out.b = b_index;
  out.kernel = MatchingKernel(options);
  const cv::Mat &ia = ta.u8, &ib = tb.u8;
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
      // Whole pixels of a: its window is read as stored, only b's is resampled.
      const Eigen::Vector2d ua(std::round(x0 + sx + i * options.grid_step_px), std::round(y0 + sy + j * options.grid_step_px));
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
  // The prepared pyramids when they were built with a border for this window and reach as many levels (a
  // pyramid of more levels serves fewer: the tracker starts at the level it is asked for).
  const auto tracked = [&](const TrackableTile& t) {
    const bool usable = t.pyramid_window_px >= options.window_px && t.pyramid_levels >= options.pyramid_levels;
    return usable ? cv::InputArray(t.pyramid) : cv::InputArray(t.u8);
  };
  if (options.track) {
    cv::calcOpticalFlowPyrLK(tracked(ta), tracked(tb), from, to, status, error, window, options.pyramid_levels, stop,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    cv::calcOpticalFlowPyrLK(tracked(tb), tracked(ta), to, back, back_status, back_error, window,
                             options.pyramid_levels, stop, cv::OPTFLOW_USE_INITIAL_FLOW);
  } else {
    status.assign(from.size(), 1), back_status.assign(from.size(), 1);
  }
  for (size_t k = 0; k < from.size(); ++k) {
    if (!status[k] || !back_status[k] || !inside(to[k], wb, hb)) continue;
    const double dx = back[k].x - from[k].x, dy = back[k].y - from[k].y;
    if (std::hypot(dx, dy) > options.max_round_trip_px) continue;
    Eigen::Vector2d e(to[k].x, to[k].y);
    const cv::Point ua(static_cast<int>(std::lround(from[k].x)), static_cast<int>(std::lround(from[k].y)));
    const Eigen::Matrix2d j = WindowMap(guess, Eigen::Vector2d(ua.x, ua.y), e);
    if (!RefinePoint(ta, tb, ua, options.window_px / 2, j, e) || (e - Eigen::Vector2d(to[k].x, to[k].y)).norm() > 0.5 ||
        !inside(cv::Point2f(static_cast<float>(e.x()), static_cast<float>(e.y())), wb, hb)) {
      continue;
    }
    out.a_px.emplace_back(ua.x, ua.y);
    out.b_px.push_back(e);
  }
  return out;
}

}  // namespace

FieldKernel MatchingKernel(const CorrespondenceOptions& options) {
  // The window's offsets -h..h, each weighing 1 / n, and the Gaussian's moments (sigma^2, 3 sigma^4, 15 sigma^6):
  // the moments of the sum of the two independent offsets.
  const int h = options.window_px / 2, n = 2 * h + 1;
  double w2 = 0.0, w4 = 0.0, w6 = 0.0;
  for (int v = -h; v <= h; ++v) w2 += std::pow(v, 2) / n, w4 += std::pow(v, 4) / n, w6 += std::pow(v, 6) / n;
  const double g2 = kRefinementSmoothingPx * kRefinementSmoothingPx, g4 = 3.0 * g2 * g2, g6 = 15.0 * g2 * g2 * g2;
  return {w2 + g2, w4 + 6.0 * w2 * g2 + g4, w6 + 15.0 * w4 * g2 + 15.0 * w2 * g4 + g6};
}

PairCorrespondences MatchOverlap(const TileImage& a, const TileImage& b, int a_index, int b_index,
                                 const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                 const CorrespondenceOptions& options) {
  options.Check();
  return MatchPrepared(TrackableImage(a, options.highpass_sigma_px), TrackableImage(b, options.highpass_sigma_px),
                       a_index, b_index, offset_px, guess, options);
}

PreparedTiles PrepareTilesForMatching(const std::vector<TileImage>& images, const CorrespondenceOptions& options) {
  options.Check();
  auto set = std::make_shared<PreparedTileSet>();
  set->tiles.resize(images.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(images.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      PreparedTileSet::Tile& tile = set->tiles[static_cast<size_t>(i)];
      tile = TrackableImage(images[static_cast<size_t>(i)], options.highpass_sigma_px);
      tile.pyramid_levels = cv::buildOpticalFlowPyramid(tile.u8, tile.pyramid, cv::Size(options.window_px, options.window_px),
                                                        options.pyramid_levels);
      tile.pyramid_window_px = options.window_px;
    }
  });
  return {std::move(set), static_cast<int>(images.size())};
}

std::vector<PairCorrespondences> MatchPreparedOverlaps(const PreparedTiles& tiles,
                                                       const std::vector<OverlapToMatch>& overlaps,
                                                       const FieldDistortion& guess,
                                                       const CorrespondenceOptions& options) {
  options.Check();
  for (const OverlapToMatch& o : overlaps) {
    if (o.a < 0 || o.b < 0 || o.a >= tiles.size || o.b >= tiles.size || !tiles.set) {
      throw std::invalid_argument("MatchOverlaps: a tile index outside the images");
    }
  }
  const std::vector<PreparedTileSet::Tile>& prepared = tiles.set->tiles;
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

std::vector<PairCorrespondences> MatchOverlaps(const std::vector<TileImage>& images,
                                               const std::vector<OverlapToMatch>& overlaps,
                                               const FieldDistortion& guess, const CorrespondenceOptions& options) {
  return MatchPreparedOverlaps(PrepareTilesForMatching(images, options), overlaps, guess, options);
}

}  // namespace fvm::imaging
