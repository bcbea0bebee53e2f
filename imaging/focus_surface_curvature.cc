#include "imaging/focus_surface_curvature.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "imaging/focus_height_maps.h"
#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {
namespace {

// A point's curvature needs at least this share of the Gaussian's weight on points out of reach of a bend and ridge.
constexpr float kMinKeptShare = 0.5f;

}  // namespace

void SurfaceCurvature(MapPool& pool, const float* laplacian_px, const float* weight_px, const float* bends_px,
                      float* curvature_px) {
  const int width = pool.width(), height = pool.height();
  const auto map = [&](const float* p) { return cv::Mat(height, width, CV_32F, const_cast<float*>(p)); };
  const cv::Mat laplacian = map(laplacian_px), weight = map(weight_px), bends = map(bends_px);
  cv::Mat curvature = map(curvature_px);
  cv::Mat bend_free(height, width, CV_8U);  // 0 at a bend
  // Into `curvature`: the local mean of the Laplacian over kSurfaceCurvaturePx at the points farther than `reach_px`
  // from a bend, by their weight (kept); returns the blur of the weights kept (a normalised convolution's total).
  const auto mean_beyond = [&](double reach_px) {
    cv::Mat distance = pool.Map(), kept = pool.Map(), product = pool.Map(), total = pool.Map();
    cv::distanceTransform(bend_free, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float *k = kept.ptr<float>(r), *p = product.ptr<float>(r);
        const float *w = weight.ptr<float>(r), *d = distance.ptr<float>(r), *l = laplacian.ptr<float>(r);
        for (int col = 0; col < width; ++col) {
          k[col] = d[col] > reach_px ? w[col] : 0.0f;
          p[col] = k[col] * l[col];
        }
      }
    });
    pool.Pass([&](int r0, int r1) { BlurredRatio(product, kept, kSurfaceCurvaturePx, r0, r1, total, curvature); },
              BlurStripeRows(kSurfaceCurvaturePx));
    return total;
  };

  // A first curvature, beyond the bends the roughness found (into `curvature`).
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      unsigned char* f = bend_free.ptr<unsigned char>(r);
      const float* b = bends.ptr<float>(r);
      for (int col = 0; col < width; ++col) f[col] = b[col] > 0.5f ? 0 : 1;
    }
  });
  mean_beyond(kCurvatureBendReachPx);
  // The ridge: where the Laplacian's local mean over kRidgeScalePx, over every weighted point, departs from that
  // curvature by more than kRidgeCut times its typical departure; its points join the bends.
  {
    const Ridge ridge = FindRidge(laplacian, weight, curvature, pool);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        unsigned char* f = bend_free.ptr<unsigned char>(r);
        const float* m = ridge.square.ptr<float>(r);
        for (int col = 0; col < width; ++col) f[col] = f[col] != 0 && m[col] <= ridge.cut ? 1 : 0;
      }
    });
  }
  // The curvature beyond the reach of the bends and the ridge, where that leaves at least kMinKeptShare of the
  // weight around a point (the Gaussian's weight over all points, `all`): not on a bend's band, whose points would
  // mix both sides, but on an isolated ridge of the noise in a wide bottom.
  const cv::Mat total = mean_beyond(kRidgeReachPx);
  cv::Mat all = pool.Map();
  pool.Pass(
      [&](int r0, int r1) {
        cv::Mat all_rows = all.rowRange(r0, r1);
        cv::GaussianBlur(weight.rowRange(r0, r1), all_rows, cv::Size(), kSurfaceCurvaturePx, 0.0, cv::BORDER_REFLECT);
      },
      BlurStripeRows(kSurfaceCurvaturePx));
  constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* c = curvature.ptr<float>(r);
      const float *t = total.ptr<float>(r), *a = all.ptr<float>(r);
      for (int col = 0; col < width; ++col)
        c[col] = t[col] > kMinKeptShare * a[col] && a[col] > 1e-3f ? c[col] : kUnknown;
    }
  });
}

Ridge FindRidge(const cv::Mat& laplacian, const cv::Mat& weight, const cv::Mat& baseline, MapPool& pool) {
  Ridge ridge{WeightedLocalMean(laplacian, weight, kRidgeScalePx, pool)};
  cv::Mat& square = ridge.square;
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* m = square.ptr<float>(r);
      if (baseline.empty()) {
        for (int col = 0; col < square.cols; ++col) m[col] *= m[col];
      } else {
        const float* c = baseline.ptr<float>(r);
        for (int col = 0; col < square.cols; ++col) m[col] = (m[col] - c[col]) * (m[col] - c[col]);
      }
    }
  });
  ridge.cut = kRidgeCut * kRidgeCut * TypicalSquare(square, weight);
  return ridge;
}

}  // namespace fvm::imaging
