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

void SurfaceCurvature(int width, int height, bool parallel, const float* laplacian_px, const float* weight_px,
                      const float* bends_px, float* const scratch[4], float* curvature_px) {
  const auto map = [&](const float* p) { return cv::Mat(height, width, CV_32F, const_cast<float*>(p)); };
  const cv::Mat laplacian = map(laplacian_px), weight = map(weight_px), bends = map(bends_px);
  cv::Mat distance = map(scratch[0]), kept = map(scratch[1]), product = map(scratch[2]), total = map(scratch[3]);
  cv::Mat curvature = map(curvature_px);
  const auto pass = [&](const auto& body, int stripe_rows = kStripeRows) {
    ForStripes(height, parallel, body, stripe_rows);
  };
  cv::Mat bend_free(height, width, CV_8U);  // 0 at a bend
  // The distance (px) of each point from the nearest point of `bend_free` 0 (into `distance`).
  const auto distances = [&] {
    cv::distanceTransform(bend_free, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  };
  // The local mean over sigma_px of the Laplacian at the points `kept` (into `mean`): the blur of their product over
  // the blur of the weights (in `total`).
  const auto local_mean = [&](double sigma_px, cv::Mat& mean) {
    pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* p = product.ptr<float>(r);
        const float *l = laplacian.ptr<float>(r), *k = kept.ptr<float>(r);
        for (int col = 0; col < width; ++col) p[col] = k[col] * l[col];
      }
    });
    pass([&](int r0, int r1) { BlurredRatio(product, kept, sigma_px, r0, r1, total, mean); },
         BlurStripeRows(sigma_px));
  };
  // The points farther than `reach_px` from a bend keep their weight.
  const auto keep_beyond = [&](double reach_px) {
    pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        float* k = kept.ptr<float>(r);
        const float *w = weight.ptr<float>(r), *d = distance.ptr<float>(r);
        for (int col = 0; col < width; ++col) k[col] = d[col] > reach_px ? w[col] : 0.0f;
      }
    });
  };

  // A first curvature, beyond the bends the roughness found (into `curvature`).
  pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      unsigned char* f = bend_free.ptr<unsigned char>(r);
      const float* b = bends.ptr<float>(r);
      for (int col = 0; col < width; ++col) f[col] = b[col] > 0.5f ? 0 : 1;
    }
  });
  distances();
  keep_beyond(kCurvatureBendReachPx);
  local_mean(kSurfaceCurvaturePx, curvature);
  // The ridge: where the Laplacian's local mean over kRidgeScalePx, over every weighted point, departs from that
  // curvature by more than kRidgeCut times its typical departure (squared, into `ridge`); its points join the bends.
  pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* k = kept.ptr<float>(r);
      const float* w = weight.ptr<float>(r);
      for (int col = 0; col < width; ++col) k[col] = w[col];
    }
  });
  cv::Mat ridge = distance;  // the distances are no longer needed
  local_mean(kRidgeScalePx, ridge);
  pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* m = ridge.ptr<float>(r);
      const float* c = curvature.ptr<float>(r);
      for (int col = 0; col < width; ++col) m[col] = (m[col] - c[col]) * (m[col] - c[col]);
    }
  });
  const float ridge_cut = kRidgeCut * kRidgeCut * TypicalSquare(ridge, weight);
  pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      unsigned char* f = bend_free.ptr<unsigned char>(r);
      const float* m = ridge.ptr<float>(r);
      for (int col = 0; col < width; ++col) f[col] = f[col] != 0 && m[col] <= ridge_cut ? 1 : 0;
    }
  });
  // The curvature beyond the reach of the bends and the ridge, where that leaves at least kMinKeptShare of the
  // weight around a point (the Gaussian's weight over all points, into `product`): not on a bend's band, whose
  // points would mix both sides, but on an isolated ridge of the noise in a wide bottom.
  distances();
  keep_beyond(kRidgeReachPx);
  local_mean(kSurfaceCurvaturePx, curvature);
  pass(
      [&](int r0, int r1) {
        cv::Mat p_rows = product.rowRange(r0, r1);
        cv::GaussianBlur(weight.rowRange(r0, r1), p_rows, cv::Size(), kSurfaceCurvaturePx, 0.0, cv::BORDER_REFLECT);
      },
      BlurStripeRows(kSurfaceCurvaturePx));
  constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      float* c = curvature.ptr<float>(r);
      const float *t = total.ptr<float>(r), *all = product.ptr<float>(r);
      for (int col = 0; col < width; ++col)
        c[col] = t[col] > kMinKeptShare * all[col] && all[col] > 1e-3f ? c[col] : kUnknown;
    }
  });
}

}  // namespace fvm::imaging
