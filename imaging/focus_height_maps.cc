#include "imaging/focus_height_maps.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "imaging/focus_surface_curvature.h"

namespace fvm::imaging {
namespace {

constexpr double kSlopeSmoothingPx = 2.0;  // sigma of the smoothing of the heights before their slope
constexpr int kScatterWindowPx = 9;
// The roughness (WindowScaleRoughness): the surface's own curvature is the Laplacian's local mean over this sigma;
// the departures from it are averaged over the box. A bend: the departures' local mean over kBendWidthPx beyond
// kBendCut times its typical size; its own departures count over kBendReachPx at kBendShare (calibrated with the
// uncertainty model's weights, focus_variation.cc, on focusgen.py seeds 11 and 12 and this project's renderer,
// focus_accuracy_test.cc).
constexpr double kCurvatureSmoothingPx = 6.0;
constexpr int kRoughnessBoxPx = 15;
constexpr float kBendCut = 3.0f;
constexpr double kBendWidthPx = 2.0;
constexpr double kBendReachPx = 4.0;
constexpr float kBendShare = 0.4f;
constexpr float kNoCurvature = std::numeric_limits<float>::quiet_NaN();
// Where the curvature is unknown, its estimate for the uncertainty of what the heights' corrections could not take
// off: the local mean of the known values over this sigma, where they make at least kCurvatureFillShare of the points.
constexpr double kCurvatureFillPx = 12.0;
constexpr float kCurvatureFillShare = 0.05f;
// The local plane (WindowScaleRoughness) is fitted where the determinant of its normal equations is at least this
// share of what as many valid points spread evenly would give (share^3 sigma^4); below it they lie too nearly on a
// line or at a point to fix a plane's slope along both axes.
constexpr double kPlaneFitConditioning = 0.05;

// Heights (mm) with holes as float maps for the filters: relative to `origin` (so that float keeps the nm of a
// stage tens of mm out), 0 in the holes, and the mask of the valid points.
struct HoleyMap {
  cv::Mat heights, valid;
  cv::Mat share;  // after Smooth: the Gaussian's weight on the valid points around each point

  HoleyMap(const std::vector<double>& z, double origin, MapPool& pool)
      : heights(pool.Map()), valid(pool.Map()), share(pool.Map()) {
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* h = heights.ptr<float>(r);
        float* v = valid.ptr<float>(r);
        const double* row = z.data() + std::size_t(r) * std::size_t(heights.cols);
        for (int col = 0; col < heights.cols; ++col) {
          const bool ok = std::isfinite(row[col]);
          h[col] = ok ? float(row[col] - origin) : 0.0f;
          v[col] = ok ? 1.0f : 0.0f;
        }
      }
    });
  }

  // The local mean of the valid points in rows r0..r1 of `out`: a Gaussian average over them only (the blur of
  // the heights over the blur of the mask).
  // The holes are 0 already, so the heights are their own product with the mask.
  void Smooth(double sigma_px, int r0, int r1, cv::Mat& out) {
    BlurredRatio(heights, valid, sigma_px, r0, r1, share, out);
  }
};

}  // namespace

void BlurredRatio(const cv::Mat& numerator, const cv::Mat& weights, double sigma_px, int r0, int r1, cv::Mat& total,
                  cv::Mat& mean) {
  cv::Mat m_rows = mean.rowRange(r0, r1), t_rows = total.rowRange(r0, r1);
  cv::GaussianBlur(numerator.rowRange(r0, r1), m_rows, cv::Size(), sigma_px, 0.0, cv::BORDER_REFLECT);
  cv::GaussianBlur(weights.rowRange(r0, r1), t_rows, cv::Size(), sigma_px, 0.0, cv::BORDER_REFLECT);
  for (int r = r0; r < r1; ++r) {
    float* m = mean.ptr<float>(r);
    const float* t = total.ptr<float>(r);
    for (int col = 0; col < mean.cols; ++col) m[col] /= std::max(t[col], 1e-6f);
  }
}

cv::Mat WeightedLocalMean(const cv::Mat& values, const cv::Mat& weights, double sigma_px, MapPool& pool) {
  cv::Mat product = pool.Map(), total = pool.Map(), mean = pool.Map();
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* p = product.ptr<float>(r);
      const float *v = values.ptr<float>(r), *w = weights.ptr<float>(r);
      for (int col = 0; col < values.cols; ++col) p[col] = v[col] * w[col];
    }
  });
  pool.Pass([&](int r0, int r1) { BlurredRatio(product, weights, sigma_px, r0, r1, total, mean); },
            BlurStripeRows(sigma_px));
  return mean;
}

float TypicalSquare(const cv::Mat& square, const cv::Mat& weight) {
  constexpr std::size_t kEvery = 7;  // prime against the image's width
  std::vector<float> sample;
  const std::size_t n = std::size_t(square.rows) * std::size_t(square.cols);
  const float *d = square.ptr<float>(), *w = weight.ptr<float>();
  for (std::size_t i = 0; i < n; i += kEvery) {
    if (w[i] > 0.0f) sample.push_back(d[i]);
  }
  if (sample.empty()) return 0.0f;
  std::nth_element(sample.begin(), sample.begin() + std::ptrdiff_t(sample.size() / 2), sample.end());
  return sample[sample.size() / 2] / 0.4549f;
}

SmoothedHeights SmoothHeights(const std::vector<double>& z, double origin, MapPool& pool) {
  HoleyMap map(z, origin, pool);
  SmoothedHeights out{map.heights, map.valid, map.share, pool.Map(), {pool.Map(), pool.Map()}};
  pool.Pass([&](int r0, int r1) { map.Smooth(kSlopeSmoothingPx, r0, r1, out.smooth); });
  pool.Pass([&](int r0, int r1) {
    cv::Mat gx_rows = out.slope.x.rowRange(r0, r1), gy_rows = out.slope.y.rowRange(r0, r1);
    cv::Sobel(out.smooth.rowRange(r0, r1), gx_rows, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(out.smooth.rowRange(r0, r1), gy_rows, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
  });
  return out;
}

cv::Mat LocalScatter(const SmoothedHeights& smoothed, MapPool& pool) {
  cv::Mat residual = pool.Map(), scatter = pool.Map();
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* o = residual.ptr<float>(r);
      const float *h = smoothed.heights.ptr<float>(r), *m = smoothed.smooth.ptr<float>(r);
      const float* v = smoothed.valid.ptr<float>(r);
      for (int col = 0; col < residual.cols; ++col) o[col] = (h[col] - m[col]) * (h[col] - m[col]) * v[col];
    }
  });
  const cv::Size box(kScatterWindowPx, kScatterWindowPx);
  cv::Mat count = pool.Map();  // valid points in the box
  pool.Pass([&](int r0, int r1) {
    cv::Mat s_rows = scatter.rowRange(r0, r1), count_rows = count.rowRange(r0, r1);
    cv::boxFilter(residual.rowRange(r0, r1), s_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
    cv::boxFilter(smoothed.valid.rowRange(r0, r1), count_rows, CV_32F, box, cv::Point(-1, -1), false,
                  cv::BORDER_REFLECT);
    for (int r = r0; r < r1; ++r) {
      float* o = scatter.ptr<float>(r);
      const float* n = count.ptr<float>(r);
      for (int col = 0; col < scatter.cols; ++col) o[col] = std::sqrt(std::max(o[col], 0.0f) / std::max(n[col], 1.0f));
    }
  });
  return scatter;
}

// The heights' roughness at the window's scale: the rms over kRoughnessBoxPx of the Laplacian of the smoothed
// heights less its own smooth local mean (the real surface's curvature, which changes slowly; what is left are
// errors shared over a window). From the smoothed heights (SmoothHeights). Beside holes the smooth heights are the
// mean of the valid points only, whose centroid lies off the pixel: on a slope that is a step of up to the slope times
// the offset, which the Laplacian took for roughness (walls with half their pixels invalid: 1.6 times their errors).
// So the smooth heights are the intercept of a plane fitted to the valid points with the same Gaussian weights
// (local linear regression [Cleveland 1979]), which holes leave unbiased on any slope; only where the points
// around a pixel fix no plane are the heights moved back along the map's slope by the centroid's offset. Moving
// them all by the map's slope (itself read from the holey mean) left the roughness on walls with half their
// pixels invalid 1.2-1.6 times their errors where the fewer the valid points, the more (focusgen.py, NA 0.3, 2 px
// texture; 0.9-1.1 with the plane). A point counts by the share of valid points around it (squared).
// A bend of the surface sharper than kCurvatureSmoothingPx (a calotte's rim: its slope turns by 24 deg within a
// pixel) is no error but a ridge in the Laplacian, four times the errors' departures on focusgen.py's stacks,
// whose local mean then spreads a shadow of the ridge (1.5 times the errors' departures) 12 px either side: the
// roughness read the rim's shape up to 15 px from it (u_z 2-3 times the errors there; walls and flats beside the
// rim covered 99-100 %). A bend bends the heights one way all along it, while the errors' departures change sign
// within a window: where the departures' own local mean (over kBendWidthPx) exceeds kBendCut times its typical
// size over the map (a robust scale: the median square, as a redescending M-estimator leaves out outliers
// [Huber 1981]), the point is a bend and is left out of the curvature's local mean and of the box. What a window
// straddling the bend errs is real, though (at NA 0.9 up to 0.3 step within 6 px of the rim on focusgen.py, within
// 2 px at NA 0.3): the bend's squared departures, spread over kBendReachPx (a 9 px window's reach), count at
// kBendShare.
// The maps a step no longer needs are let go of (release, or the end of a block) where it ends, so that the next
// step's maps take their memory instead of fresh pages: with the caller's slope and scatter, at most 15 maps are
// alive at once (during the plane fit, whose normal equations take seven).
WindowScaleMaps WindowScaleRoughness(SmoothedHeights smoothed, MapPool& pool) {
  cv::Mat valid = std::move(smoothed.valid);
  // Each point's weight, written over the share of valid points around it that it is made of (a point reads only
  // its own share).
  cv::Mat weight = std::move(smoothed.share);
  cv::Mat plane = pool.Map();  // the smooth heights as the intercept of the local plane
  {
    const cv::Mat heights = std::move(smoothed.heights), smooth = std::move(smoothed.smooth);
    const Slope slope = std::move(smoothed.slope);
    cv::Mat gauss = cv::getGaussianKernel(int(std::lround(8 * kSlopeSmoothingPx)) | 1, kSlopeSmoothingPx, CV_32F);
    cv::Mat moment = gauss.clone();  // the kernel times the offset of its tap: the first moment of the valid points
    for (int k = 0; k < moment.rows; ++k) moment.at<float>(k) *= float(k - moment.rows / 2);
    const auto filter = [](const cv::Mat& in, cv::Mat& out, const cv::Mat& kx, const cv::Mat& ky) {
      cv::sepFilter2D(in, out, CV_32F, kx, ky, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT);
    };
    cv::Mat second = gauss.clone();  // the kernel times its tap's offset squared: second moments
    for (int k = 0; k < second.rows; ++k) second.at<float>(k) *= float((k - second.rows / 2) * (k - second.rows / 2));
    // The valid points' moments about each point (first: along x and y; second: xx, yy, xy) and the heights' first
    // moments: the local plane's normal equations.
    cv::Mat ox = pool.Map(), oy = pool.Map(), sxx = pool.Map(), syy = pool.Map(), sxy = pool.Map();
    cv::Mat tx = pool.Map(), ty = pool.Map();
    pool.Pass([&](int r0, int r1) {
      cv::Mat x = ox.rowRange(r0, r1), y = oy.rowRange(r0, r1), xx = sxx.rowRange(r0, r1),
              yy = syy.rowRange(r0, r1), xy = sxy.rowRange(r0, r1), hx = tx.rowRange(r0, r1), hy = ty.rowRange(r0, r1);
      filter(valid.rowRange(r0, r1), x, moment, gauss);
      filter(valid.rowRange(r0, r1), y, gauss, moment);
      filter(valid.rowRange(r0, r1), xx, second, gauss);
      filter(valid.rowRange(r0, r1), yy, gauss, second);
      filter(valid.rowRange(r0, r1), xy, moment, moment);
      filter(heights.rowRange(r0, r1), hx, moment, gauss);
      filter(heights.rowRange(r0, r1), hy, gauss, moment);
      for (int r = r0; r < r1; ++r) {
        float* s = plane.ptr<float>(r);
        float* w = weight.ptr<float>(r);
        const float *m = smooth.ptr<float>(r), *v = valid.ptr<float>(r), *px = ox.ptr<float>(r), *py = oy.ptr<float>(r);
        const float *gx = slope.x.ptr<float>(r), *gy = slope.y.ptr<float>(r);
        const float *pxx = sxx.ptr<float>(r), *pyy = syy.ptr<float>(r), *pxy = sxy.ptr<float>(r);
        const float *qx = tx.ptr<float>(r), *qy = ty.ptr<float>(r);
        for (int col = 0; col < smooth.cols; ++col) {
          const float share = std::max(w[col], 1e-6f);
          s[col] = m[col] - (gx[col] * px[col] + gy[col] * py[col]) / share;
          const double s0 = share, sx = px[col], sy = py[col], xx2 = pxx[col], yy2 = pyy[col], xy2 = pxy[col];
          const double minor = xx2 * yy2 - xy2 * xy2;
          const double det = s0 * minor - sx * (sx * yy2 - xy2 * sy) + sy * (sx * xy2 - xx2 * sy);
          if (det > kPlaneFitConditioning * s0 * s0 * s0 * kSlopeSmoothingPx * kSlopeSmoothingPx * kSlopeSmoothingPx *
                        kSlopeSmoothingPx) {
            const double t0 = double(m[col]) * s0, t1 = qx[col], t2 = qy[col];
            s[col] = float((t0 * minor - sx * (t1 * yy2 - xy2 * t2) + sy * (t1 * xy2 - xx2 * t2)) / det);
          }
          w[col] = v[col] * std::min(share, 1.0f) * std::min(share, 1.0f);
        }
      }
    });
  }
  cv::Mat plane_x = pool.Map(), plane_y = pool.Map();  // its slope
  pool.Pass([&](int r0, int r1) {
    cv::Mat x_rows = plane_x.rowRange(r0, r1), y_rows = plane_y.rowRange(r0, r1);
    cv::Sobel(plane.rowRange(r0, r1), x_rows, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(plane.rowRange(r0, r1), y_rows, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
  });
  plane.release();
  cv::Mat laplacian = pool.Map();  // at the valid points, 0 in the holes
  {
    cv::Mat yy = pool.Map();
    pool.Pass([&](int r0, int r1) {
      cv::Mat xx_rows = laplacian.rowRange(r0, r1), yy_rows = yy.rowRange(r0, r1);
      cv::Sobel(plane_x.rowRange(r0, r1), xx_rows, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
      cv::Sobel(plane_y.rowRange(r0, r1), yy_rows, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
      for (int r = r0; r < r1; ++r) {
        float* l = laplacian.ptr<float>(r);
        const float *y = yy.ptr<float>(r), *v = valid.ptr<float>(r);
        for (int col = 0; col < laplacian.cols; ++col) l[col] = (l[col] + y[col]) * v[col];
      }
    });
  }
  plane_x.release(), plane_y.release(), valid.release();
  // The Laplacian's weighted local mean and the departures from it, first over every valid point, then over those
  // that are no bend (weights `kept`; the bends' own squared departures in `bend`). The departures' mean square
  // over the box, over the points that are no bend, plus the bends' spread over their reach.
  cv::Mat departures = pool.Map();
  const auto depart = [&](const cv::Mat& weights) {
    const cv::Mat mean = WeightedLocalMean(laplacian, weights, kCurvatureSmoothingPx, pool);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* d = departures.ptr<float>(r);
        const float *l = laplacian.ptr<float>(r), *m = mean.ptr<float>(r);
        for (int col = 0; col < laplacian.cols; ++col) d[col] = l[col] - m[col];
      }
    });
  };
  // The departures' local mean (signed) over kBendWidthPx, squared: the points where it exceeds the cut are bends.
  depart(weight);
  cv::Mat kept = pool.Map(), bend = pool.Map(), is_bend = pool.Map();
  {
    cv::Mat bending = WeightedLocalMean(departures, weight, kBendWidthPx, pool);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* m = bending.ptr<float>(r);
        for (int col = 0; col < bending.cols; ++col) m[col] = m[col] * m[col];
      }
    });
    const float cut = kBendCut * kBendCut * TypicalSquare(bending, weight);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* k = kept.ptr<float>(r);
        const float *b = bending.ptr<float>(r), *w = weight.ptr<float>(r);
        for (int col = 0; col < kept.cols; ++col) k[col] = b[col] <= cut ? w[col] : 0.0f;
      }
    });
  }
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float *o = bend.ptr<float>(r), *flag = is_bend.ptr<float>(r);
      const float *d = departures.ptr<float>(r), *k = kept.ptr<float>(r), *w = weight.ptr<float>(r);
      for (int col = 0; col < bend.cols; ++col) {
        o[col] = d[col] * d[col] * (w[col] - k[col]);
        flag[col] = w[col] > k[col] ? 1.0f : 0.0f;
      }
    }
  });
  weight.release();
  depart(kept);
  // The surface's own curvature at a scale larger than the roughness's, NaN within reach of a bend or of the ridge
  // a bend leaves (focus_surface_curvature.h).
  WindowScaleMaps out;
  cv::Mat& curvature = out.curvature = pool.Map();
  SurfaceCurvature(pool, laplacian.ptr<float>(), kept.ptr<float>(), is_bend.ptr<float>(), curvature.ptr<float>());
  laplacian.release(), is_bend.release();
  // The same, filled where unknown by the local mean of the known values over kCurvatureFillPx (NaN where none lies
  // within reach).
  {
    cv::Mat known = pool.Map(), known_values = pool.Map(), fill_total = pool.Map();
    cv::Mat& filled = out.filled_curvature = pool.Map();
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float *k = known.ptr<float>(r), *v = known_values.ptr<float>(r);
        const float* l = curvature.ptr<float>(r);
        for (int col = 0; col < known.cols; ++col) {
          k[col] = std::isfinite(l[col]) ? 1.0f : 0.0f;
          v[col] = std::isfinite(l[col]) ? l[col] : 0.0f;
        }
      }
    });
    pool.Pass(
        [&](int r0, int r1) {
          BlurredRatio(known_values, known, kCurvatureFillPx, r0, r1, fill_total, filled);
          for (int r = r0; r < r1; ++r) {
            float* f = filled.ptr<float>(r);
            const float* t = fill_total.ptr<float>(r);
            for (int col = 0; col < filled.cols; ++col) f[col] = t[col] >= kCurvatureFillShare ? f[col] : kNoCurvature;
          }
        },
        BlurStripeRows(kCurvatureFillPx));
  }
  // The departures' squares at the points that are no bend, summed over the box (`sum`) with the points' weights
  // (`count`); the bends' squared departures spread over their reach (`near`).
  cv::Mat sum = pool.Map(), count = pool.Map(), near = pool.Map();
  {
    cv::Mat square = pool.Map();
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* o = square.ptr<float>(r);
        const float *d = departures.ptr<float>(r), *k = kept.ptr<float>(r);
        for (int col = 0; col < square.cols; ++col) o[col] = d[col] * d[col] * k[col];
      }
    });
    const cv::Size box(kRoughnessBoxPx, kRoughnessBoxPx);
    pool.Pass([&](int r0, int r1) {
      cv::Mat sum_rows = sum.rowRange(r0, r1), count_rows = count.rowRange(r0, r1);
      cv::boxFilter(square.rowRange(r0, r1), sum_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
      cv::boxFilter(kept.rowRange(r0, r1), count_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
    });
  }
  pool.Pass([&](int r0, int r1) {
    cv::Mat near_rows = near.rowRange(r0, r1);
    cv::GaussianBlur(bend.rowRange(r0, r1), near_rows, cv::Size(), kBendReachPx, 0.0, cv::BORDER_REFLECT);
  });
  cv::Mat& roughness = out.roughness = pool.Map();
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      const float *s = sum.ptr<float>(r), *n = count.ptr<float>(r), *b = near.ptr<float>(r);
      float* o = roughness.ptr<float>(r);
      for (int col = 0; col < roughness.cols; ++col)
        o[col] = std::sqrt(std::max(s[col], 0.0f) / std::max(n[col], 1e-3f) +
                           kBendShare * kBendShare * std::max(b[col], 0.0f));
    }
  });
  return out;
}

}  // namespace fvm::imaging
