#include "imaging/focus_phase_bias.h"

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/dense_decomposition.h"
#include "imaging/focus_peak.h"
#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {
namespace {

using Terms = Eigen::Matrix<double, PhaseBias::kTerms, 1>;
using TermMatrix = Eigen::Matrix<double, PhaseBias::kTerms, PhaseBias::kTerms>;

// Level: a slope below this many steps per pixel (on focusgen.py's flat, tilted by 0.012 step per px, the
// phase sweeps a period over about 85 px; a calotte's bottom stays below it within 12 px of its centre).
constexpr double kLevelSlope = 0.03;
// The correction's fade with the slope (steps per px): exp(-(slope / kFadeSlope)^2).
constexpr double kFadeSlope = 0.05;
// Departure from even steps (share of a step) beyond which the phase is not read: 0.05 step moves a bias of a
// few hundredths of a step at the first harmonic by less than a hundredth of that.
constexpr double kUnevenSteps = 0.05;
// The local plane's box (px), wider than a stripe of equal phase on the gently tilted faces where the bias is
// largest, so that the plane does not follow the bias (a Gaussian of sigma 20 px did as well on focusgen.py's
// stacks; a box's sums cost the same whatever its side); the blocks of the cluster sandwich (px), about twice the
// distance at which the heights' errors correlate 0.5 on focusgen.py's stacks.
constexpr int kPlaneBoxPx = 61;
constexpr int kBlockPx = 16;
// Errors shared across a block's border are missed by the sandwich, the more so the longer they correlate: against
// the bias fitted at each height's TRUE phase on focusgen.py's level flats, the estimate erred 1.19-1.46 times what
// the sandwich over kBlockPx said at NA 0.9 with a 0.8 um floor (seeds 11, 12), 0.94-1.26 times the sandwich over
// blocks twice as wide. So the correction's uncertainty takes the larger of the two (Bester, Conley and Hansen
// 2011: spatial dependence needs large blocks; Cameron and Miller 2015: grow the clusters while the standard error
// grows). The shrinkage keeps the narrow blocks' sandwich: with 10-17 wide blocks on a 256 px map its chi-square
// scatters (with few clusters the sandwich errs low, and the shrinkage rose from 0.72 to 0.94 on some NA 0.9 flats).
constexpr int kWideBlockPx = 2 * kBlockPx;
// The estimation runs on a grid of at most this many points a side (every s-th pixel of a larger map; the
// box and the blocks shrink with it), so that its cost stays a few milliseconds on any map.
constexpr int kEstimationSide = 512;
// Declined below this many level points (in pixels of the map), this many blocks, or where any of kPhaseBins
// bins of the phase holds less than a quarter of its even share.
constexpr double kMinPoints = 1000.0;
constexpr int kMinBlocks = 10;
constexpr int kPhaseBins = 8;
// A local plane is fitted where at least this share of its box holds level points and they spread over both
// axes (the determinant of its normal equations at least kPlaneConditioning of an even spread's).
constexpr double kMinBoxShare = 0.125;
constexpr double kPlaneConditioning = 0.05;
// The level points' scatter about their planes (LevelScatter): an rms over a box of this side, where at least
// kMinScatterShare of it holds level points with a plane.
constexpr int kScatterBoxPx = 31;
constexpr double kMinScatterShare = 0.1;

double PhaseOf(double z, double origin, double step) {
  const double t = (z - origin) / step;
  return t - std::round(t);
}

// The phase of pixel i, from the smoothed heights where given.
double PhaseOfPixel(const PhaseBiasInput& in, std::size_t i) {
  if (in.phase_heights) return PhaseOf(in.origin_mm + double(in.phase_heights[i]), in.origin_mm, in.step_mm);
  return PhaseOf((*in.z_mm)[i], in.origin_mm, in.step_mm);
}

Terms Harmonics(double phase) {
  static_assert(PhaseBias::kHarmonics == 3);
  const double c1 = std::cos(2.0 * std::numbers::pi * phase), s1 = std::sin(2.0 * std::numbers::pi * phase);
  const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * s1 * c1;  // the higher harmonics by the angle sums
  Terms f;
  f << c1, s1, c2, s2, c2 * c1 - s2 * s1, s2 * c1 + c2 * s1;
  return f;
}

cv::Mat Box(const cv::Mat& in, int side) {
  cv::Mat out;
  cv::boxFilter(in, out, CV_64F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  return out;
}

// The level points on the estimation grid (every `stride`-th pixel; weight 1 in `w`), their heights in steps and
// the harmonics of their phase (`signals`), and the coordinates from the grid's centre.
struct LevelGrid {
  int stride = 1, rows = 0, cols = 0, box = 3;
  cv::Mat w, x, y;
  std::vector<cv::Mat> signals;
};

LevelGrid SampleLevelPoints(const PhaseBiasInput& in) {
  LevelGrid grid;
  const int stride = std::max(1, (std::max(in.width, in.height) + kEstimationSide - 1) / kEstimationSide);
  const int cols = (in.width + stride - 1) / stride, rows = (in.height + stride - 1) / stride;
  grid.stride = stride, grid.rows = rows, grid.cols = cols;
  grid.box = std::max(3, (kPlaneBoxPx / stride) | 1);
  const std::vector<double>& z = *in.z_mm;
  grid.w = cv::Mat(rows, cols, CV_64F, 0.0);
  grid.signals.resize(1 + PhaseBias::kTerms);
  for (cv::Mat& m : grid.signals) m = cv::Mat(rows, cols, CV_64F, 0.0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = std::size_t(r) * stride * std::size_t(in.width) + std::size_t(c) * stride;
      const double g = std::hypot(in.slope_x[i], in.slope_y[i]) / in.step_mm;
      if (!std::isfinite(z[i]) || !(g < kLevelSlope)) continue;
      grid.w.at<double>(r, c) = 1.0;
      grid.signals[0].at<double>(r, c) = (z[i] - in.origin_mm) / in.step_mm;
      const Terms f = Harmonics(PhaseOfPixel(in, i));
      for (int j = 0; j < PhaseBias::kTerms; ++j) grid.signals[std::size_t(j) + 1].at<double>(r, c) = f(j);
    }
  }
  grid.x = cv::Mat(rows, cols, CV_64F), grid.y = cv::Mat(rows, cols, CV_64F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) grid.x.at<double>(r, c) = c - 0.5 * cols, grid.y.at<double>(r, c) = r - 0.5 * rows;
  }
  return grid;
}

// A level point whose box fixes a plane, and the first row of the inverse of that plane's normal equations
// (centred on it): the plane's intercept is that row times the box sums of a signal (its sum and first moments).
struct PlanePoint {
  int r, c;
  double row[3];
};

std::vector<PlanePoint> PlanePoints(const LevelGrid& grid) {
  const cv::Mat &w = grid.w, &x = grid.x, &y = grid.y;
  const int box = grid.box;
  const cv::Mat wx = w.mul(x), wy = w.mul(y);
  const cv::Mat s0 = Box(w, box), sx = Box(wx, box), sy = Box(wy, box), sxx = Box(wx.mul(x), box),
                syy = Box(wy.mul(y), box), sxy = Box(wx.mul(y), box);
  std::vector<PlanePoint> points;
  const double even = double(box) * double(box) / 12.0;  // the second moment of points spread evenly over the box
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      if (w.at<double>(r, c) == 0.0) continue;
      const double n = s0.at<double>(r, c);
      if (n < kMinBoxShare * box * box) continue;
      const double px = x.at<double>(r, c), py = y.at<double>(r, c);
      const double mx = sx.at<double>(r, c) - px * n, my = sy.at<double>(r, c) - py * n;
      const double mxx = sxx.at<double>(r, c) - 2.0 * px * sx.at<double>(r, c) + px * px * n;
      const double myy = syy.at<double>(r, c) - 2.0 * py * sy.at<double>(r, c) + py * py * n;
      const double mxy = sxy.at<double>(r, c) - px * sy.at<double>(r, c) - py * sx.at<double>(r, c) + px * py * n;
      Eigen::Matrix3d m;
      m << n, mx, my, mx, mxx, mxy, my, mxy, myy;
      if (!(m.determinant() > kPlaneConditioning * n * n * n * even * even)) continue;
      const Eigen::Matrix3d inverse = m.inverse();
      points.push_back({r, c, {inverse(0, 0), inverse(0, 1), inverse(0, 2)}});
    }
  }
  return points;
}

// The departures of each signal from its local plane at the points: signals.size() values per point.
std::vector<double> Departures(const LevelGrid& grid, const std::vector<PlanePoint>& points) {
  const std::size_t n = grid.signals.size();
  std::vector<double> departure(points.size() * n);
  for (std::size_t s = 0; s < n; ++s) {
    const cv::Mat ws = grid.w.mul(grid.signals[s]);
    const cv::Mat t0 = Box(ws, grid.box), tx = Box(ws.mul(grid.x), grid.box), ty = Box(ws.mul(grid.y), grid.box);
    for (std::size_t p = 0; p < points.size(); ++p) {
      const PlanePoint& q = points[p];
      const double px = grid.x.at<double>(q.r, q.c), py = grid.y.at<double>(q.r, q.c);
      const double a = t0.at<double>(q.r, q.c), b = tx.at<double>(q.r, q.c) - px * a,
                   c = ty.at<double>(q.r, q.c) - py * a;
      const double intercept = q.row[0] * a + q.row[1] * b + q.row[2] * c;
      departure[p * n + s] = grid.signals[s].at<double>(q.r, q.c) - intercept;
    }
  }
  return departure;
}

// Whether each of kPhaseBins bins of the points' phase holds at least a quarter of its even share.
bool PhasesSpread(const LevelGrid& grid, const std::vector<PlanePoint>& points) {
  std::array<int, kPhaseBins> bins{};
  for (const PlanePoint& q : points) {
    const double phase = std::atan2(grid.signals[2].at<double>(q.r, q.c), grid.signals[1].at<double>(q.r, q.c)) /
                         (2.0 * std::numbers::pi);  // -0.5..0.5
    bins[std::size_t(std::clamp(int(std::floor((phase + 0.5) * kPhaseBins)), 0, kPhaseBins - 1))]++;
  }
  return *std::min_element(bins.begin(), bins.end()) * 4 * kPhaseBins >= int(points.size());
}

// The cluster sandwich of the coefficients (steps^2; Liang and Zeger 1986): the scores of the residuals summed per
// block of `block` grid px, between the inverse normal equations; and how many blocks held points.
std::pair<TermMatrix, int> ClusterSandwich(const LevelGrid& grid, const std::vector<PlanePoint>& points,
                                           const std::vector<double>& departure, const Terms& coefficients,
                                           const TermMatrix& inverse, int block) {
  const std::size_t n = grid.signals.size();
  std::unordered_map<long, Terms> scores;
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Eigen::Map<const Terms> f(departure.data() + p * n + 1);
    const double residual = departure[p * n] - f.dot(coefficients);
    const long key = long(points[p].r / block) * 100000L + long(points[p].c / block);
    scores.try_emplace(key, Terms::Zero()).first->second += f * residual;
  }
  TermMatrix meat = TermMatrix::Zero();
  for (const auto& [key, g] : scores) meat.noalias() += g * g.transpose();
  const double blocks = double(scores.size());
  return {blocks / (blocks - 1.0) * inverse * meat * inverse, int(scores.size())};
}

// bias.level_scatter: the points' departures from their local planes less the bias `fitted` (steps), rms over
// kScatterBoxPx, in mm.
void ScatterAboutPlanes(const LevelGrid& grid, const std::vector<PlanePoint>& points,
                        const std::vector<double>& departure, const Terms& fitted, double step_mm, PhaseBias& bias) {
  const std::size_t n = grid.signals.size();
  const int scatter_box = std::max(3, (kScatterBoxPx / grid.stride) | 1);
  cv::Mat square(grid.rows, grid.cols, CV_64F, 0.0), counted(grid.rows, grid.cols, CV_64F, 0.0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    const double* d = departure.data() + p * n;
    const double r = d[0] - Eigen::Map<const Terms>(d + 1).dot(fitted);
    square.at<double>(points[p].r, points[p].c) = r * r;
    counted.at<double>(points[p].r, points[p].c) = 1.0;
  }
  const cv::Mat sum = Box(square, scatter_box), count = Box(counted, scatter_box);
  bias.grid_stride = grid.stride, bias.grid_cols = grid.cols;
  bias.level_scatter.assign(std::size_t(grid.rows) * std::size_t(grid.cols), std::numeric_limits<float>::quiet_NaN());
  const double min_count = kMinScatterShare * scatter_box * scatter_box;
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double k = count.at<double>(r, c);
      if (k >= min_count && grid.w.at<double>(r, c) > 0.0) {
        bias.level_scatter[std::size_t(r) * std::size_t(grid.cols) + std::size_t(c)] =
            float(std::sqrt(sum.at<double>(r, c) / k) * step_mm);
      }
    }
  }
}

}  // namespace

double PhaseBias::At(double phase) const {
  if (!applied) return 0.0;
  const Terms f = Harmonics(phase);
  return Eigen::Map<const Terms>(coefficients.data()).dot(f);
}

double PhaseBias::Uncertainty(double phase) const {
  if (!applied) return 0.0;
  const Terms f = Harmonics(phase);
  using Covariance = Eigen::Map<const Eigen::Matrix<double, kTerms, kTerms, Eigen::RowMajor>>;
  const Covariance narrow(covariance.data()), wide(wide_covariance.data());
  return std::sqrt(std::max({f.dot(narrow * f), f.dot(wide * f), 0.0}));
}

double PhaseBias::Rms() const {
  if (!applied) return 0.0;
  double sum = 0.0;  // each harmonic's cos and sin average to a half over a period
  for (double c : coefficients) sum += 0.5 * c * c;
  return std::sqrt(sum);
}

double PhaseBias::Fade(double slope_mm_per_px) const {
  if (!applied) return 0.0;
  return PhaseBiasFade(slope_mm_per_px, step_mm);
}

double PhaseBiasFade(double slope_mm_per_px, double step_mm) {
  if (!(step_mm > 0.0)) return 0.0;
  const double s = slope_mm_per_px / step_mm / kFadeSlope;
  return std::exp(-s * s);
}

double PhaseBias::LevelScatter(int row, int col) const {
  if (level_scatter.empty()) return std::numeric_limits<double>::quiet_NaN();
  return level_scatter[std::size_t(row / grid_stride) * std::size_t(grid_cols) + std::size_t(col / grid_stride)];
}

double PredictedPhaseBiasRms(double rise1, double rise2, double power) {
  if (!(rise1 > 0.0) || !(rise2 > rise1)) return 0.0;
  const auto phase = [](int k) { return (k + 0.5) / kPredictionPhases - 0.5; };
  const auto curve = [](double b, double c, double u) { return 1.0 + b * std::abs(u) + c * u * u; };
  const auto median = [](std::array<double, kPredictionPhases>& v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[kPredictionPhases / 2 - 1] + v[kPredictionPhases / 2]);
  };
  // The curve's rises over its best image, one and two images out, medians over the phase.
  const auto rises = [&](double b, double c) {
    std::array<double, kPredictionPhases> one, two;
    for (int k = 0; k < kPredictionPhases; ++k) {
      const double t = phase(k), top = curve(b, c, t);
      one[std::size_t(k)] = 0.5 * (curve(b, c, -1.0 - t) + curve(b, c, 1.0 - t)) / top - 1.0;
      two[std::size_t(k)] = 0.5 * (curve(b, c, -2.0 - t) + curve(b, c, 2.0 - t)) / top - 1.0;
    }
    return std::pair{median(one), median(two)};
  };
  // Over the V's share of the curve (41 values), the size that gives rise1 (bisection: the rises grow with it);
  // kept, the share whose rise two images out is nearest rise2.
  double best_b = 0.0, best_c = 0.0, best_miss = std::numeric_limits<double>::infinity();
  for (int j = 0; j <= 40; ++j) {
    const double share = j / 40.0;
    double lo = 1e-3, hi = 100.0, size = 1.0;
    for (int it = 0; it < 40; ++it) {
      size = std::sqrt(lo * hi);
      (rises(size * share, size * (1.0 - share)).first < rise1 ? lo : hi) = size;
    }
    const double miss = std::abs(rises(size * share, size * (1.0 - share)).second - rise2);
    if (miss < best_miss) best_miss = miss, best_b = size * share, best_c = size * (1.0 - share);
  }
  // The fit's vertex through the curve's measures (P^(-3/2)) at five images 0..4, the surface t past image 2.
  const std::vector<double> z = {0.0, 1.0, 2.0, 3.0, 4.0};
  std::array<double, kPredictionPhases> bias;
  double mean = 0.0;
  for (int k = 0; k < kPredictionPhases; ++k) {
    const double t = phase(k);
    std::array<double, 5> f;
    for (int i = 0; i < 5; ++i) f[std::size_t(i)] = std::pow(curve(best_b, best_c, (i - 2) - t), -1.5);
    bias[std::size_t(k)] = PowerVertex(z, 2, f, 0.0, power) - (2.0 + t);
    mean += bias[std::size_t(k)] / kPredictionPhases;
  }
  double sum = 0.0;
  for (double v : bias) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / kPredictionPhases);
}

PhaseBias EstimatePhaseBias(const PhaseBiasInput& in) {
  PhaseBias bias;
  bias.step_mm = in.step_mm;
  const LevelGrid grid = SampleLevelPoints(in);
  const std::vector<PlanePoint> points = PlanePoints(grid);
  const int stride = grid.stride;
  bias.points = int(points.size());
  if (in.uneven_steps > kUnevenSteps) {
    bias.reason = fmt::format("the stack's z steps are uneven (an image lies {:.2f} step off an even grid), so a "
                              "height's phase between two images is not known", in.uneven_steps);
    return bias;
  }
  if (double(points.size()) * stride * stride < kMinPoints) {
    bias.reason = "too few level points (" + std::to_string(points.size() * std::size_t(stride) * stride) + " px)";
    return bias;
  }
  if (!PhasesSpread(grid, points)) {
    bias.reason = "too few phases among the level points (a face level within a step, or a small level area)";
    return bias;
  }
  const std::vector<double> departure = Departures(grid, points);
  const std::size_t n = grid.signals.size();
  TermMatrix a = TermMatrix::Zero();
  Terms b = Terms::Zero();
  const auto regressors = [&](std::size_t p) { return Eigen::Map<const Terms>(departure.data() + p * n + 1); };
  for (std::size_t p = 0; p < points.size(); ++p) {
    const auto f = regressors(p);
    a.noalias() += f * f.transpose();
    b += f * departure[p * n];
  }
  if (!a.allFinite() || !b.allFinite()) {
    bias.reason = "a height that is not a number among the level points";
    return bias;
  }
  const auto solver = Decompose<Eigen::LDLT<TermMatrix>>(a, "the phase bias's normal equations");
  if (solver.info() != Eigen::Success || !(solver.rcond() > 1e-6)) {
    bias.reason = "the phases seen do not fix the harmonics";
    return bias;
  }
  const Terms coefficients = solver.solve(b);  // steps
  const TermMatrix inverse = solver.solve(TermMatrix::Identity());
  const auto [covariance, blocks] =
      ClusterSandwich(grid, points, departure, coefficients, inverse, std::max(1, kBlockPx / stride));
  if (blocks < kMinBlocks) {
    bias.reason = "too few blocks of level points";
    return bias;
  }
  if (!covariance.allFinite()) {
    bias.reason = "the phase bias's covariance is not finite";
    return bias;
  }
  const auto spread = Decompose<Eigen::LDLT<TermMatrix>>(covariance, "the phase bias's covariance");
  const double chi2 = coefficients.dot(spread.solve(coefficients));
  bias.shrinkage = std::max(0.0, 1.0 - double(PhaseBias::kTerms - 2) / chi2);
  if (!(bias.shrinkage > 0.0)) {
    bias.reason = "no bias beyond its own noise";
    return bias;
  }
  bias.applied = true;
  ScatterAboutPlanes(grid, points, departure, bias.shrinkage * coefficients, in.step_mm, bias);
  // The wide blocks' sandwich, where there are enough of them (else the narrow one's stands alone).
  auto [wide, wide_blocks] =
      ClusterSandwich(grid, points, departure, coefficients, inverse, std::max(1, kWideBlockPx / stride));
  if (wide_blocks < kMinBlocks || !wide.allFinite()) wide = covariance;
  const double scale = bias.shrinkage * bias.shrinkage * in.step_mm * in.step_mm;
  for (int j = 0; j < PhaseBias::kTerms; ++j) {
    bias.coefficients[std::size_t(j)] = bias.shrinkage * coefficients(j) * in.step_mm;
    for (int k = 0; k < PhaseBias::kTerms; ++k) {
      bias.covariance[std::size_t(j * PhaseBias::kTerms + k)] = scale * covariance(j, k);
      bias.wide_covariance[std::size_t(j * PhaseBias::kTerms + k)] = scale * wide(j, k);
    }
  }
  return bias;
}

void CorrectPhaseBias(const PhaseBias& bias, const PhaseBiasInput& in, std::vector<double>& z_mm,
                      std::vector<float>& u_mm) {
  u_mm.assign(z_mm.size(), 0.0f);
  if (!bias.applied) return;
  // The bias and its uncertainty tabulated over the phase (kTable intervals, interpolated linearly: the error of
  // three harmonics so sampled is below 1e-4 of the bias), and the fade's exponent per squared slope: a few
  // nanoseconds a pixel instead of the harmonics and the covariance's quadratic form.
  constexpr int kTable = 1024;
  std::vector<double> at(kTable + 2), u(kTable + 2);
  for (int k = 0; k <= kTable + 1; ++k) {
    const double phase = -0.5 + double(k) / kTable;
    at[std::size_t(k)] = bias.At(phase), u[std::size_t(k)] = bias.Uncertainty(phase);
  }
  const double fade_scale = 1.0 / (in.step_mm * kFadeSlope * in.step_mm * kFadeSlope);
  ForStripes(in.height, in.parallel, [&](int r0, int r1) {
    for (std::size_t i = std::size_t(r0) * std::size_t(in.width); i < std::size_t(r1) * std::size_t(in.width); ++i) {
      if (!std::isfinite(z_mm[i])) continue;
      const double slope2 = double(in.slope_x[i]) * in.slope_x[i] + double(in.slope_y[i]) * in.slope_y[i];
      const double fade = std::exp(-slope2 * fade_scale);  // bias.Fade
      if (!(fade > 1e-3)) continue;
      const double t = (PhaseOfPixel(in, i) + 0.5) * kTable;
      const int k = std::clamp(int(t), 0, kTable);
      const double share = t - k;
      const std::size_t j = std::size_t(k);
      u_mm[i] = float(fade * (u[j] + share * (u[j + 1] - u[j])));
      z_mm[i] -= fade * (at[j] + share * (at[j + 1] - at[j]));
    }
  });
}

}  // namespace fvm::imaging
