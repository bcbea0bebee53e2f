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

// Heights (mm) with holes as float maps for the filters (buffers 0 to 2): relative to `origin` (so that float
// keeps the nm of a stage tens of mm out), 0 in the holes, and the mask of the valid points.
struct HoleyMap {
  cv::Mat heights, valid, work;

  HoleyMap(const std::vector<double>& z, double origin, MapBuffers& buffers)
      : heights(buffers[0]), valid(buffers[1]), work(buffers[2]) {
    buffers.Pass([&](int r0, int r1) {
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
    BlurredRatio(heights, valid, sigma_px, r0, r1, work, out);
  }
};

// The local mean of `values` weighted by `weights` over a Gaussian of sigma_px, into `mean`: the blur of values x
// weights over the blur of the weights. `product` and `total` are scratch; the product is complete before any band
// blurs it, since a band's blur reads the rows beside it.
void WeightedLocalMean(const cv::Mat& values, const cv::Mat& weights, double sigma_px, MapBuffers& buffers,
                       cv::Mat& product, cv::Mat& total, cv::Mat& mean) {
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* p = product.ptr<float>(r);
      const float *v = values.ptr<float>(r), *w = weights.ptr<float>(r);
      for (int col = 0; col < values.cols; ++col) p[col] = v[col] * w[col];
    }
  });
  buffers.Pass([&](int r0, int r1) { BlurredRatio(product, weights, sigma_px, r0, r1, total, mean); },
               BlurStripeRows(sigma_px));
}

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

Slope SlopePerPixel(const std::vector<double>& z, double origin, MapBuffers& buffers) {
  HoleyMap map(z, origin, buffers);
  cv::Mat smooth = buffers[3];
  Slope slope{buffers[4], buffers[6]};
  buffers.Pass([&](int r0, int r1) { map.Smooth(kSlopeSmoothingPx, r0, r1, smooth); });
  buffers.Pass([&](int r0, int r1) {
    cv::Mat gx_rows = slope.x.rowRange(r0, r1), gy_rows = slope.y.rowRange(r0, r1);
    cv::Sobel(smooth.rowRange(r0, r1), gx_rows, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(smooth.rowRange(r0, r1), gy_rows, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
  });
  return slope;
}

// The rms of the heights about their smooth local mean, over a window around each valid point (buffer 5).
cv::Mat LocalScatter(const std::vector<double>& z, double origin, MapBuffers& buffers) {
  HoleyMap map(z, origin, buffers);
  cv::Mat residual = buffers[3], scatter = buffers[5];
  buffers.Pass([&](int r0, int r1) {
    map.Smooth(kSlopeSmoothingPx, r0, r1, residual);
    for (int r = r0; r < r1; ++r) {
      float* o = residual.ptr<float>(r);
      const float* h = map.heights.ptr<float>(r);
      const float* v = map.valid.ptr<float>(r);
      for (int col = 0; col < residual.cols; ++col) o[col] = (h[col] - o[col]) * (h[col] - o[col]) * v[col];
    }
  });
  const cv::Size box(kScatterWindowPx, kScatterWindowPx);
  buffers.Pass([&](int r0, int r1) {
    cv::Mat s_rows = scatter.rowRange(r0, r1), count_rows = map.work.rowRange(r0, r1);
    cv::boxFilter(residual.rowRange(r0, r1), s_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
    cv::boxFilter(map.valid.rowRange(r0, r1), count_rows, CV_32F, box, cv::Point(-1, -1), false,
                  cv::BORDER_REFLECT);
    for (int r = r0; r < r1; ++r) {
      float* o = scatter.ptr<float>(r);
      const float* count = map.work.ptr<float>(r);
      for (int col = 0; col < scatter.cols; ++col)
        o[col] = std::sqrt(std::max(o[col], 0.0f) / std::max(count[col], 1.0f));
    }
  });
  return scatter;
}

// The heights' roughness at the window's scale (buffer 3): the rms over kRoughnessBoxPx of the Laplacian of the
// smoothed heights less its own smooth local mean (the real surface's curvature, which changes slowly; what is
// left are errors shared over a window). Takes what SlopePerPixel leaves: the heights, the mask, its blur and the
// smooth heights (buffers 0 to 3) and their slope (4 and 6). Beside holes the smooth heights are the mean of the
// valid points only, whose centroid lies off the pixel: on a slope that is a step of up to the slope times the
// offset, which the Laplacian took for roughness (walls with half their pixels invalid: 1.6 times their errors).
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
cv::Mat WindowScaleRoughness(const Slope& slope, MapBuffers& buffers) {
  cv::Mat heights = buffers[0], valid = buffers[1], weight = buffers[2], smooth = buffers[3];
  cv::Mat a = buffers[7], b = buffers[8], c = buffers[9], roughness = buffers[3];
  cv::Mat gauss = cv::getGaussianKernel(int(std::lround(8 * kSlopeSmoothingPx)) | 1, kSlopeSmoothingPx, CV_32F);
  cv::Mat moment = gauss.clone();  // the kernel times the offset of its tap: the first moment of the valid points
  for (int k = 0; k < moment.rows; ++k) moment.at<float>(k) *= float(k - moment.rows / 2);
  const auto filter = [](const cv::Mat& in, cv::Mat& out, const cv::Mat& kx, const cv::Mat& ky) {
    cv::sepFilter2D(in, out, CV_32F, kx, ky, cv::Point(-1, -1), 0.0, cv::BORDER_REFLECT);
  };
  cv::Mat second = gauss.clone();  // the kernel times its tap's offset squared: second moments
  for (int k = 0; k < second.rows; ++k) second.at<float>(k) *= float((k - second.rows / 2) * (k - second.rows / 2));
  cv::Mat sxx = buffers[11], syy = buffers[12], sxy = buffers[13], tx = buffers[14], ty = buffers[15];
  buffers.Pass([&](int r0, int r1) {
    cv::Mat a_rows = a.rowRange(r0, r1), b_rows = b.rowRange(r0, r1), xx = sxx.rowRange(r0, r1),
            yy = syy.rowRange(r0, r1), xy = sxy.rowRange(r0, r1), hx = tx.rowRange(r0, r1), hy = ty.rowRange(r0, r1);
    filter(valid.rowRange(r0, r1), a_rows, moment, gauss);
    filter(valid.rowRange(r0, r1), b_rows, gauss, moment);
    filter(valid.rowRange(r0, r1), xx, second, gauss);
    filter(valid.rowRange(r0, r1), yy, gauss, second);
    filter(valid.rowRange(r0, r1), xy, moment, moment);
    filter(heights.rowRange(r0, r1), hx, moment, gauss);
    filter(heights.rowRange(r0, r1), hy, gauss, moment);
    for (int r = r0; r < r1; ++r) {
      float* s = c.ptr<float>(r);
      float* w = weight.ptr<float>(r);
      const float *m = smooth.ptr<float>(r), *v = valid.ptr<float>(r), *ox = a.ptr<float>(r), *oy = b.ptr<float>(r);
      const float *gx = slope.x.ptr<float>(r), *gy = slope.y.ptr<float>(r);
      const float *pxx = sxx.ptr<float>(r), *pyy = syy.ptr<float>(r), *pxy = sxy.ptr<float>(r);
      const float *qx = tx.ptr<float>(r), *qy = ty.ptr<float>(r);
      for (int col = 0; col < smooth.cols; ++col) {
        const float share = std::max(w[col], 1e-6f);
        s[col] = m[col] - (gx[col] * ox[col] + gy[col] * oy[col]) / share;
        const double s0 = share, sx = ox[col], sy = oy[col], xx2 = pxx[col], yy2 = pyy[col], xy2 = pxy[col];
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
  buffers.Pass([&](int r0, int r1) {
    cv::Mat a_rows = a.rowRange(r0, r1), b_rows = b.rowRange(r0, r1);
    cv::Sobel(c.rowRange(r0, r1), a_rows, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(c.rowRange(r0, r1), b_rows, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
  });
  buffers.Pass([&](int r0, int r1) {  // the Laplacian (buffer 0)
    cv::Mat xx = heights.rowRange(r0, r1), yy = smooth.rowRange(r0, r1);
    cv::Sobel(a.rowRange(r0, r1), xx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(b.rowRange(r0, r1), yy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    for (int r = r0; r < r1; ++r) {
      float* l = heights.ptr<float>(r);
      const float *y = smooth.ptr<float>(r), *v = valid.ptr<float>(r);
      for (int col = 0; col < heights.cols; ++col) l[col] = (l[col] + y[col]) * v[col];
    }
  });
  // The Laplacian's weighted local mean and the departures from it (buffer 3), first over every valid point, then
  // over those that are no bend (weights in buffer 1, the mask being no longer needed; the bends' own squared
  // departures in buffer 10). The departures' mean square over the box, over the points that are no bend, plus the
  // bends' spread over their reach.
  cv::Mat kept = valid;
  const auto departures = [&](const cv::Mat& weights) {
    WeightedLocalMean(heights, weights, kCurvatureSmoothingPx, buffers, c, b, a);
    buffers.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* d = roughness.ptr<float>(r);
        const float *l = heights.ptr<float>(r), *m = a.ptr<float>(r);
        for (int col = 0; col < heights.cols; ++col) d[col] = l[col] - m[col];
      }
    });
  };
  // The departures' local mean (signed) over kBendWidthPx, squared (buffer 9): the points where it exceeds the cut
  // are bends.
  departures(weight);
  WeightedLocalMean(roughness, weight, kBendWidthPx, buffers, c, b, a);
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* o = c.ptr<float>(r);
      const float* m = a.ptr<float>(r);
      for (int col = 0; col < c.cols; ++col) o[col] = m[col] * m[col];
    }
  });
  const float cut = kBendCut * kBendCut * TypicalSquare(c, weight);
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* k = kept.ptr<float>(r);
      const float *bend = c.ptr<float>(r), *w = weight.ptr<float>(r);
      for (int col = 0; col < c.cols; ++col) k[col] = bend[col] <= cut ? w[col] : 0.0f;
    }
  });
  cv::Mat bend = buffers[10], is_bend = buffers[12];
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float *o = bend.ptr<float>(r), *flag = is_bend.ptr<float>(r);
      const float *d = roughness.ptr<float>(r), *k = kept.ptr<float>(r), *w = weight.ptr<float>(r);
      for (int col = 0; col < c.cols; ++col) {
        o[col] = d[col] * d[col] * (w[col] - k[col]);
        flag[col] = w[col] > k[col] ? 1.0f : 0.0f;
      }
    }
  });
  departures(kept);
  // The surface's own curvature (buffer 11) at a scale larger than the roughness's, NaN within reach of a bend or
  // of the ridge a bend leaves (focus_surface_curvature.h).
  cv::Mat curvature = buffers[11];
  {
    float* const scratch[4] = {buffers[13].ptr<float>(), buffers[14].ptr<float>(), b.ptr<float>(), c.ptr<float>()};
    SurfaceCurvature(c.cols, c.rows, buffers.parallel, heights.ptr<float>(), kept.ptr<float>(), is_bend.ptr<float>(),
                     scratch, curvature.ptr<float>());
  }
  // The same, filled where unknown by the local mean of the known values over kCurvatureFillPx (buffer 15; NaN where
  // none lies within reach).
  cv::Mat known = buffers[12], known_values = buffers[13], filled = buffers[15];
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float *k = known.ptr<float>(r), *v = known_values.ptr<float>(r);
      const float* l = curvature.ptr<float>(r);
      for (int col = 0; col < c.cols; ++col) {
        k[col] = std::isfinite(l[col]) ? 1.0f : 0.0f;
        v[col] = std::isfinite(l[col]) ? l[col] : 0.0f;
      }
    }
  });
  cv::Mat fill_total = buffers[14];
  buffers.Pass(
      [&](int r0, int r1) {
        BlurredRatio(known_values, known, kCurvatureFillPx, r0, r1, fill_total, filled);
        for (int r = r0; r < r1; ++r) {
          float* f = filled.ptr<float>(r);
          const float* t = fill_total.ptr<float>(r);
          for (int col = 0; col < c.cols; ++col) f[col] = t[col] >= kCurvatureFillShare ? f[col] : kNoCurvature;
        }
      },
      BlurStripeRows(kCurvatureFillPx));
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* o = c.ptr<float>(r);
      const float *d = roughness.ptr<float>(r), *k = kept.ptr<float>(r);
      for (int col = 0; col < c.cols; ++col) o[col] = d[col] * d[col] * k[col];
    }
  });
  const cv::Size box(kRoughnessBoxPx, kRoughnessBoxPx);
  buffers.Pass([&](int r0, int r1) {
    cv::Mat a_rows = a.rowRange(r0, r1), b_rows = b.rowRange(r0, r1);
    cv::boxFilter(c.rowRange(r0, r1), a_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
    cv::boxFilter(kept.rowRange(r0, r1), b_rows, CV_32F, box, cv::Point(-1, -1), false, cv::BORDER_REFLECT);
  });
  buffers.Pass([&](int r0, int r1) {
    cv::Mat c_rows = c.rowRange(r0, r1);
    cv::GaussianBlur(bend.rowRange(r0, r1), c_rows, cv::Size(), kBendReachPx, 0.0, cv::BORDER_REFLECT);
  });
  buffers.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      const float *sum = a.ptr<float>(r), *count = b.ptr<float>(r), *near = c.ptr<float>(r);
      float* o = roughness.ptr<float>(r);
      for (int col = 0; col < roughness.cols; ++col)
        o[col] = std::sqrt(std::max(sum[col], 0.0f) / std::max(count[col], 1e-3f) +
                           kBendShare * kBendShare * std::max(near[col], 0.0f));
    }
  });
  return roughness;
}

}  // namespace fvm::imaging
