#include "imaging/calotte_detection.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <string>

#include "core/dense_decomposition.h"
#include "core/input_error.h"
#include "core/statistics.h"

namespace fvm::imaging {
namespace {

// Face samples: enough to pin a plane to a small fraction of the noise, few enough to be quick on 4k x 4k.
constexpr std::size_t kFaceSamples = 200000;
constexpr std::size_t kScoreSamples = 5000;
constexpr int kLmedsTrials = 300;

// printf-style messages: imaging does not link fmt.
__attribute__((format(printf, 1, 2))) std::string Format(const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

// Least squares plane z = a + b x + c y through the points with keep[i]; coordinates relative to `origin`.
Eigen::Vector3d LeastSquaresPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<bool>& keep) {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!keep[i]) continue;
    const Eigen::Vector3d a(1.0, points[i].x(), points[i].y());
    ata += a * a.transpose();
    atb += a * points[i].z();
  }
  return Decompose<Eigen::LDLT<Eigen::Matrix3d>>(ata, "the calotte detection's base plane").solve(atb);
}

FacePlane FitFace(const HeightMap& map, std::uint64_t seed) {
  std::size_t valid = 0;
  for (const double z : map.z_mm) valid += std::isfinite(z);
  if (valid == 0) throw InputError("the height map holds no valid point (all NaN); nothing to find calottes in");
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(valid) / kFaceSamples))));
  // Coordinates relative to the map's middle keep the 3 x 3 normal equations well conditioned.
  const double xm = map.x0_mm + 0.5 * (map.size_x - 1) * map.dx_mm;
  const double ym = map.y0_mm + 0.5 * (map.size_y - 1) * map.dy_mm;
  std::vector<Eigen::Vector3d> samples;
  for (int iy = 0; iy < map.size_y; iy += stride) {
    for (int ix = 0; ix < map.size_x; ix += stride) {
      const double z = map.at(ix, iy);
      if (std::isfinite(z)) samples.emplace_back(map.x0_mm + ix * map.dx_mm - xm, map.y0_mm + iy * map.dy_mm - ym, z);
    }
  }
  if (samples.size() < 10) {
    throw InputError(
        Format("the height map has only %zu valid points; too few to find the face the calottes are cut into", valid));
  }

  // Least median of squares over planes through 3 samples: no threshold to guess, and it holds while the face
  // is more than half of the map.
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, samples.size() - 1);
  std::vector<std::size_t> score;
  for (std::size_t i = 0; i < std::min(kScoreSamples, samples.size()); ++i) score.push_back(pick(rng));
  // Should every trial be degenerate (the valid points on one line), a level plane at the median height.
  std::vector<double> heights;
  for (const auto& p : samples) heights.push_back(p.z());
  Eigen::Vector3d best(HighMedian(std::move(heights)), 0.0, 0.0);
  double best_median = std::numeric_limits<double>::infinity();
  std::vector<double> r2(score.size());
  for (int t = 0; t < kLmedsTrials; ++t) {
    Eigen::Matrix3d a;
    Eigen::Vector3d b;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = samples[pick(rng)];
      a.row(k) << 1.0, p.x(), p.y();
      b[k] = p.z();
    }
    const auto lu = Decompose<Eigen::FullPivLU<Eigen::Matrix3d>>(a, "the calotte detection's plane sample");
    if (lu.rank() < 3) continue;
    const Eigen::Vector3d plane = lu.solve(b);
    for (std::size_t i = 0; i < score.size(); ++i) {
      const Eigen::Vector3d& p = samples[score[i]];
      const double r = p.z() - plane[0] - plane[1] * p.x() - plane[2] * p.y();
      r2[i] = r * r;
    }
    const double m = Median(r2);
    if (m < best_median) best_median = m, best = plane;
  }

  // Refine by least squares on the points within 3.5 robust sigmas, until that set settles.
  std::vector<bool> keep(samples.size(), false);
  double sigma = 1.4826 * std::sqrt(best_median);
  for (int round = 0; round < 20; ++round) {
    const double threshold = std::max(3.5 * sigma, 1e-7);
    std::vector<bool> next(samples.size());
    std::vector<double> abs_r;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Eigen::Vector3d& p = samples[i];
      const double r = std::abs(p.z() - best[0] - best[1] * p.x() - best[2] * p.y());
      next[i] = r <= threshold;
      if (next[i]) abs_r.push_back(r);
    }
    if (abs_r.size() < 3) break;
    if (next == keep) break;
    keep = std::move(next);
    best = LeastSquaresPlane(samples, keep);
    // The median absolute residual of a trimmed normal sample underestimates sigma by little (3.5 sigma keeps
    // 99.95 %), so no correction.
    std::vector<double> kept_r;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const Eigen::Vector3d& p = samples[i];
      if (keep[i]) kept_r.push_back(std::abs(p.z() - best[0] - best[1] * p.x() - best[2] * p.y()));
    }
    sigma = 1.4826 * Median(kept_r);
  }
  FacePlane face;
  face.b = best[1];
  face.c = best[2];
  face.a = best[0] - face.b * xm - face.c * ym;
  face.sigma_mm = sigma;
  face.points = static_cast<std::size_t>(std::count(keep.begin(), keep.end(), true));
  return face;
}

// Row by row: top (largest y) to bottom, left to right; a row holds the centres within half the largest
// diameter in y of its first one.
void SortRowByRow(std::vector<DetectedCalotte>& calottes, double row_tolerance_mm) {
  std::sort(calottes.begin(), calottes.end(), [](const DetectedCalotte& a, const DetectedCalotte& b) {
    return a.fit.centre_mm.y() > b.fit.centre_mm.y();
  });
  for (std::size_t start = 0; start < calottes.size();) {
    std::size_t end = start + 1;
    while (end < calottes.size() &&
           calottes[start].fit.centre_mm.y() - calottes[end].fit.centre_mm.y() < row_tolerance_mm) {
      ++end;
    }
    std::sort(
        calottes.begin() + static_cast<std::ptrdiff_t>(start), calottes.begin() + static_cast<std::ptrdiff_t>(end),
        [](const DetectedCalotte& a, const DetectedCalotte& b) { return a.fit.centre_mm.x() < b.fit.centre_mm.x(); });
    start = end;
  }
  for (std::size_t i = 0; i < calottes.size(); ++i) calottes[i].id = static_cast<int>(i) + 1;
}

}  // namespace

void CalotteDetectionOptions::Check() const {
  if (!(min_diameter_mm > 0) || !(max_diameter_mm >= min_diameter_mm) || !std::isfinite(max_diameter_mm)) {
    throw std::invalid_argument("calotte detection: the diameter range must be positive with min <= max");
  }
  if (!(min_depth_mm >= 0)) throw std::invalid_argument("calotte detection: the depth threshold must be >= 0");
  if (min_points < 5) throw std::invalid_argument("calotte detection: a sphere needs at least 5 points");
  fit.Check();
}

CalotteDetection DetectCalottes(const HeightMap& map, const CalotteDetectionOptions& options) {
  options.Check();
  if (map.size_x <= 0 || map.size_y <= 0 ||
      map.z_mm.size() != static_cast<std::size_t>(map.size_x) * static_cast<std::size_t>(map.size_y)) {
    throw InputError(Format("the height map's size (%d x %d) does not match its %zu heights", map.size_x, map.size_y,
                            map.z_mm.size()));
  }
  if (!(map.dx_mm > 0) || !(map.dy_mm > 0)) {
    throw InputError("the height map has no pixel size; give it (e.g. --pixel-mm) so that calottes can be measured");
  }
  CalotteDetection out;
  out.face = FitFace(map, options.seed);
  const FacePlane& face = out.face;
  out.min_depth_mm = options.min_depth_mm > 0 ? options.min_depth_mm : std::max(8.0 * face.sigma_mm, 5e-4);

  // The depression mask: valid points deeper than the threshold below the face.
  cv::Mat mask(map.size_y, map.size_x, CV_8U);
  for (int iy = 0; iy < map.size_y; ++iy) {
    auto* row = mask.ptr<std::uint8_t>(iy);
    const double y = map.y0_mm + iy * map.dy_mm;
    const double row_face = face.a + face.c * y;
    for (int ix = 0; ix < map.size_x; ++ix) {
      const double z = map.at(ix, iy);
      row[ix] = std::isfinite(z) && row_face + face.b * (map.x0_mm + ix * map.dx_mm) - z > out.min_depth_mm ? 255 : 0;
    }
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);

  for (int k = 1; k < n; ++k) {
    const int area = stats.at<int>(k, cv::CC_STAT_AREA);
    if (area < options.min_points) continue;  // a speck or a spike: not worth a line in the report
    const int left = stats.at<int>(k, cv::CC_STAT_LEFT), top = stats.at<int>(k, cv::CC_STAT_TOP);
    const int width = stats.at<int>(k, cv::CC_STAT_WIDTH), height = stats.at<int>(k, cv::CC_STAT_HEIGHT);
    const Eigen::Vector2d extent(width * map.dx_mm, height * map.dy_mm);
    const bool at_border = left == 0 || top == 0 || left + width == map.size_x || top + height == map.size_y;
    RejectedRegion region{Eigen::Vector2d(map.x0_mm + (left + 0.5 * (width - 1)) * map.dx_mm,
                                          map.y0_mm + (top + 0.5 * (height - 1)) * map.dy_mm),
                          extent, static_cast<std::size_t>(area), ""};
    const double largest = extent.maxCoeff(), smallest = extent.minCoeff();
    const double fill = area * map.dx_mm * map.dy_mm / (M_PI / 4 * extent.x() * extent.y());
    if (largest > 1.1 * options.max_diameter_mm) {
      region.reason = Format(
          "%.3f x %.3f mm is larger than a calotte (max diameter %g mm): an edge, a step or "
          "calottes run together",
          extent.x(), extent.y(), options.max_diameter_mm);
    } else if (largest < options.min_diameter_mm) {
      region.reason = Format("%.3f x %.3f mm is smaller than a calotte (min diameter %g mm)", extent.x(), extent.y(),
                             options.min_diameter_mm);
    } else if (!at_border && smallest < 0.7 * largest) {
      region.reason =
          Format("%.3f x %.3f mm is not round: a scratch, or two calottes run together", extent.x(), extent.y());
    } else if (!at_border && fill < 0.5) {
      region.reason = Format("only %.0f %% of its round outline is below the face: not a dimple", 100 * fill);
    }
    if (!region.reason.empty()) {
      out.rejected.push_back(region);
      continue;
    }

    DetectedCalotte calotte;
    calotte.extent_mm = extent;
    calotte.at_border = at_border;
    std::vector<Eigen::Vector3d> points;
    points.reserve(static_cast<std::size_t>(area));
    for (int iy = top; iy < top + height; ++iy) {
      const int* row = labels.ptr<int>(iy);
      for (int ix = left; ix < left + width; ++ix) {
        if (row[ix] != k) continue;
        const double x = map.x0_mm + ix * map.dx_mm, y = map.y0_mm + iy * map.dy_mm, z = map.at(ix, iy);
        points.emplace_back(x, y, z);
        calotte.depth_mm = std::max(calotte.depth_mm, face.Height(x, y) - z);
      }
    }
    try {
      calotte.fit = FitSphere(points, options.fit);
    } catch (const InputError& e) {
      region.reason = std::string("no sphere: ") + e.what();
      out.rejected.push_back(region);
      continue;
    }
    const Eigen::Vector2d offset = calotte.fit.centre_mm.head<2>() - region.centre_mm;
    if (!at_border && offset.norm() > 0.5 * largest) {
      region.reason =
          Format("the sphere's centre lies %.3f mm from the dimple's middle: not a spherical dimple", offset.norm());
      out.rejected.push_back(region);
      continue;
    }
    out.calottes.push_back(std::move(calotte));
  }
  SortRowByRow(out.calottes, 0.5 * options.max_diameter_mm);
  return out;
}

}  // namespace fvm::imaging
