#include "imaging/tile_registration.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

namespace fvm::imaging {
namespace {

// Overlaps narrower than this give no usable correlation peak.
constexpr int kMinOverlapPx = 8;

cv::Mat View(const TileImage& image) {
  // A read-only header on the Eigen buffer: OpenCV never writes through it.
  return cv::Mat(static_cast<int>(image.rows()), static_cast<int>(image.cols()), CV_32F,
                 const_cast<float*>(image.data()));
}

// Removes what does not belong to the scene and differs between two tiles at the same place: the mean and slow
// illumination changes (a tilted part), by subtracting a low-pass. Intensity images (all pixels positive) are
// matched in the logarithm, where the camera's shading (vignetting) is a smooth term added to the scene rather
// than a gain on it: the low-pass of shaded texture is the texture's low-pass shifted by sigma^2 grad(g) / g, in
// opposite directions in A and B, and that biased every pair of a row the same way (0.010 px a pair under 30 %
// vignetting, 1 um over 16 tiles of 6 um pixels; 0.000 px in the logarithm).
cv::Mat HighPass(const cv::Mat& crop, double sigma) {
  cv::Mat out;
  crop.convertTo(out, CV_32F);
  double lowest = 0.0;
  cv::minMaxLoc(out, &lowest);
  if (lowest > 0.0) cv::log(out, out);
  if (sigma > 0.0) {
    cv::Mat low;
    cv::GaussianBlur(out, low, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
    out -= low;
  } else {
    out -= cv::mean(out)[0];
  }
  return out;
}

// Where two tiles overlap when b's top-left corner sits at `whole` in a's frame, both crops high-passed; none
// when the overlap is narrower than kMinOverlapPx.
struct Overlap {
  cv::Rect in_a, in_b;
  cv::Mat a, b;
};

std::optional<Overlap> CropOverlap(const TileImage& a, const TileImage& b, const Eigen::Vector2i& whole,
                                   double sigma) {
  const int dx = whole.x(), dy = whole.y();
  const int x0 = std::max(0, dx), x1 = std::min(static_cast<int>(a.cols()), dx + static_cast<int>(b.cols()));
  const int y0 = std::max(0, dy), y1 = std::min(static_cast<int>(a.rows()), dy + static_cast<int>(b.rows()));
  if (x1 - x0 < kMinOverlapPx || y1 - y0 < kMinOverlapPx) return std::nullopt;
  Overlap out;
  out.in_a = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  out.in_b = cv::Rect(x0 - dx, y0 - dy, out.in_a.width, out.in_a.height);
  out.a = HighPass(View(a)(out.in_a), sigma);
  out.b = HighPass(View(b)(out.in_b), sigma);
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

// The 8 taps of Lanczos-4 interpolation at fraction f in [0, 1): weight j multiplies the sample at j - 3,
// normalised to sum 1 as OpenCV's INTER_LANCZOS4 does. Its pass band is flat to ~0.3 cycles / px, where bicubic
// interpolation already shifts the phase: with bicubic the refined shifts carried a bias of ~0.01-0.04 px that
// repeats at every pair with the same fraction, and so adds up along a row of tiles.
cv::Mat LanczosTaps(double f) {
  cv::Mat taps(1, 8, CV_32F);
  double sum = 0.0;
  std::array<double, 8> w{};
  for (int j = 0; j < 8; ++j) {
    const double x = f - (j - 3);
    w[static_cast<size_t>(j)] =
        std::abs(x) < 1e-12 ? 1.0
                            : 4.0 * std::sin(std::numbers::pi * x) * std::sin(std::numbers::pi * x / 4.0) /
                                  (std::numbers::pi * std::numbers::pi * x * x);
    sum += w[static_cast<size_t>(j)];
  }
  for (int j = 0; j < 8; ++j) taps.at<float>(0, j) = static_cast<float>(w[static_cast<size_t>(j)] / sum);
  return taps;
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

// B's interior: `margin` px in from every side. ShiftedCrop reaches 3 px before and 4 px after a pixel, so a
// margin of 4 + ceil(|e|) keeps a shift by e inside A.
std::optional<cv::Rect> Interior(const cv::Mat& b, int margin) {
  const cv::Rect inner(margin, margin, b.cols - 2 * margin, b.rows - 2 * margin);
  if (inner.width < kMinOverlapPx || inner.height < kMinOverlapPx) return std::nullopt;
  return inner;
}

// Sub-pixel shift by inverse-compositional Gauss-Newton on sum (A(v + e) - B(v))^2 over B's interior: the
// Jacobian is B's gradient, so it and the 2 x 2 normal matrix are computed once; each step only resamples A.
// Returns false when it does not settle within 2 px of the start, and the phase-correlation estimate stands.
bool RefineShift(const cv::Mat& a, const cv::Mat& b, double tolerance_px, Eigen::Vector2d& e) {
  constexpr double kWander = 2.0;
  const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(e.cwiseAbs().maxCoeff() + kWander)));
  if (!inner) return false;
  // Central differences (Sobel's 1/8 scale undone) of B, taken from B's own pixels around the interior.
  cv::Mat gx, gy;
  cv::Sobel(b(*inner), gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(b(*inner), gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  const cv::Mat target = b(*inner);
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
  if (!(h.determinant() > 1e-12 * h.trace() * h.trace())) return false;
  const Eigen::LDLT<Eigen::Matrix2d> solve(h);
  Eigen::Vector2d estimate = e;
  for (int iteration = 0; iteration < 20; ++iteration) {
    const cv::Mat warped = ShiftedCrop(a, estimate, *inner);
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
    if ((estimate - e).norm() > kWander) return false;  // wandered off the peak: not the same match
    if (step.norm() < tolerance_px) break;
  }
  e = estimate;
  return true;
}

// Normalised cross-correlation of the aligned overlap: near 1 for the same scene under noise and uneven light,
// near 0 for unrelated images. Unlike the phase-correlation peak it does not depend on the overlap's size.
double AlignedCorrelation(const cv::Mat& a, const cv::Mat& b, const Eigen::Vector2d& e) {
  const auto inner = Interior(b, 4 + static_cast<int>(std::ceil(e.cwiseAbs().maxCoeff())));
  if (!inner) return 0.0;
  cv::Mat score;
  cv::matchTemplate(b(*inner), ShiftedCrop(a, e, *inner), score, cv::TM_CCOEFF_NORMED);
  return score.at<float>(0, 0);
}

}  // namespace

void RegistrationOptions::Check() const {
  if (!(min_quality >= -1.0 && min_quality <= 1.0)) throw std::invalid_argument("min_quality must be in [-1, 1]");
  if (!(max_correction > 0.0 && max_correction <= 0.5)) throw std::invalid_argument("max_correction: (0, 0.5]");
  if (!(highpass_sigma_px >= 0.0)) throw std::invalid_argument("highpass_sigma_px must be >= 0");
}

PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options) {
  options.Check();
  PairRegistration pair;
  pair.nominal_px = nominal_px;
  const Eigen::Vector2i nominal_whole = nominal_px.array().round().cast<int>();
  const std::optional<Overlap> nominal = CropOverlap(a, b, nominal_whole, options.highpass_sigma_px);
  if (!nominal) return pair;

  Eigen::Vector2d offset;
  if (options.crop_to_overlap) {
    const auto [e, response] = PhaseShift(nominal->a, nominal->b);
    pair.response = response;
    offset = nominal_whole.cast<double>() + e;
  } else {
    // Whole frames (cropped to a common size): the correlation finds the offset modulo the frame size; take the
    // representative nearest the nominal offset.
    const cv::Rect common(0, 0, static_cast<int>(std::min(a.cols(), b.cols())),
                          static_cast<int>(std::min(a.rows(), b.rows())));
    const auto [e, response] = PhaseShift(HighPass(View(a)(common), options.highpass_sigma_px),
                                          HighPass(View(b)(common), options.highpass_sigma_px));
    pair.response = response;
    offset = e;
    offset.x() += common.width * std::round((nominal_px.x() - e.x()) / common.width);
    offset.y() += common.height * std::round((nominal_px.y() - e.y()) / common.height);
  }
  const double limit = options.max_correction * std::min(nominal->in_a.width, nominal->in_a.height);
  if ((offset - nominal_px).cwiseAbs().maxCoeff() > limit) return pair;
  // Crop again where the images really overlap, to the whole pixel: the shift left to refine is at most half a
  // pixel, so the refinement and the quality lose only a few pixels of a narrow overlap to their margins.
  const Eigen::Vector2i whole = offset.array().round().cast<int>();
  const std::optional<Overlap> overlap =
      whole == nominal_whole ? nominal : CropOverlap(a, b, whole, options.highpass_sigma_px);
  if (!overlap) return pair;
  Eigen::Vector2d e = offset - whole.cast<double>();
  if (options.refine) {
    // Coarse to fine: the phase-correlation peak can be a pixel off, outside the basin of Gauss-Newton on fine
    // texture (a quarter period); blurred crops widen the basin, then the full-resolution pass sets the sub-pixel.
    cv::Mat blur_a, blur_b;
    cv::GaussianBlur(overlap->a, blur_a, cv::Size(0, 0), 2.5);
    cv::GaussianBlur(overlap->b, blur_b, cv::Size(0, 0), 2.5);
    Eigen::Vector2d refined = e;
    // The coarse pass only needs to land in the fine pass' basin; the fine one stops well below the noise.
    if (RefineShift(blur_a, blur_b, 0.05, refined) && RefineShift(overlap->a, overlap->b, 2e-3, refined)) {
      e = refined;
    }
  }
  offset = whole.cast<double>() + e;
  pair.quality = AlignedCorrelation(overlap->a, overlap->b, e);
  pair.offset_px = offset;
  pair.accepted = pair.quality >= options.min_quality;
  return pair;
}

TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs) {
  const int n = static_cast<int>(nominal_px.size());
  // Groups of tiles joined by accepted pairs (union-find); each group's root is its earliest tile.
  std::vector<int> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int i) {
    while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    return i;
  };
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    const int ra = find(pair.a), rb = find(pair.b);
    if (ra != rb) parent[static_cast<size_t>(std::max(ra, rb))] = std::min(ra, rb);
  }
  TilePositions out;
  out.positions_px = nominal_px;
  out.registered.assign(static_cast<size_t>(n), false);
  out.anchor.resize(static_cast<size_t>(n));
  // Unknowns: every tile that is not its group's anchor.
  std::vector<int> unknown(static_cast<size_t>(n), -1);
  int m = 0;
  for (int i = 0; i < n; ++i) {
    out.anchor[static_cast<size_t>(i)] = find(i);
    if (find(i) != i) unknown[static_cast<size_t>(i)] = m++;
  }
  for (int i = 0; i < n; ++i) {
    // A tile is registered when its position comes from images: it is linked to its group, or it anchors the
    // first group (whose position is where the measurement's coordinates start, by definition).
    out.registered[static_cast<size_t>(i)] = unknown[static_cast<size_t>(i)] >= 0 || i == 0;
  }
  if (m == 0) return out;
  // Normal equations of sum w |p_b - p_a - o|^2: a weighted graph Laplacian, x and y separate with one matrix.
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(m, 2);
  for (const auto& pair : pairs) {
    if (!pair.accepted) continue;
    const double w = std::max(pair.quality, 1e-6);
    const int ua = unknown[static_cast<size_t>(pair.a)], ub = unknown[static_cast<size_t>(pair.b)];
    const Eigen::RowVector2d o = pair.offset_px.transpose();
    if (ua >= 0) {
      triplets.emplace_back(ua, ua, w);
      rhs.row(ua) -= w * o;
    } else {
      rhs.row(ub) += w * nominal_px[static_cast<size_t>(pair.a)].transpose();
    }
    if (ub >= 0) {
      triplets.emplace_back(ub, ub, w);
      rhs.row(ub) += w * o;
    } else {
      rhs.row(ua) += w * nominal_px[static_cast<size_t>(pair.b)].transpose();
    }
    if (ua >= 0 && ub >= 0) {
      triplets.emplace_back(ua, ub, -w);
      triplets.emplace_back(ub, ua, -w);
    }
  }
  Eigen::SparseMatrix<double> normal(m, m);
  normal.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) throw std::runtime_error("tile positions: singular normal equations");
  const Eigen::MatrixX2d solution = solver.solve(rhs);
  for (int i = 0; i < n; ++i) {
    const int u = unknown[static_cast<size_t>(i)];
    if (u >= 0) out.positions_px[static_cast<size_t>(i)] = solution.row(u).transpose();
  }
  return out;
}

RegistrationResult RegisterTileGrid(const std::vector<TileImage>& images, const std::vector<GridTile>& tiles,
                                    const RegistrationOptions& options) {
  if (images.size() != tiles.size()) throw std::invalid_argument("RegisterTileGrid: one image per tile");
  options.Check();
  std::map<std::pair<int, int>, int> at;
  for (size_t i = 0; i < tiles.size(); ++i) at[{tiles[i].row, tiles[i].col}] = static_cast<int>(i);
  RegistrationResult result;
  std::vector<Eigen::Vector2d> nominal;
  for (size_t i = 0; i < tiles.size(); ++i) {
    nominal.push_back(tiles[i].nominal_px);
    for (const auto& [dr, dc] : {std::pair{0, 1}, std::pair{1, 0}}) {
      const auto it = at.find({tiles[i].row + dr, tiles[i].col + dc});
      if (it == at.end()) continue;
      PairRegistration pair;
      pair.a = static_cast<int>(i);
      pair.b = it->second;
      result.pairs.push_back(pair);
    }
  }
  // Pairs are independent: each writes only its own slot, so the result does not depend on the thread count.
  const auto register_range = [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      PairRegistration& pair = result.pairs[static_cast<size_t>(k)];
      const size_t a = static_cast<size_t>(pair.a), b = static_cast<size_t>(pair.b);
      pair = RegisterPair(images[a], images[b], tiles[b].nominal_px - tiles[a].nominal_px, options);
      pair.a = static_cast<int>(a);
      pair.b = static_cast<int>(b);
    }
  };
  const cv::Range all(0, static_cast<int>(result.pairs.size()));
  if (options.parallel) {
    cv::parallel_for_(all, register_range);
  } else {
    register_range(all);
  }
  result.positions = SolveTilePositions(nominal, result.pairs);
  return result;
}

}  // namespace fvm::imaging
