#include "imaging/focus_slope_beside_bends.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "imaging/focus_stack_curves.h"
#include "imaging/focus_surface_curvature.h"

namespace fvm::imaging {

void SlopeBesideBends(MapPool& pool, const float* smooth_px, const float* slope_x_px, const float* slope_y_px,
                      const float* valid_px, double step_mm, double share, float* beside_x_px, float* beside_y_px) {
  const int width = pool.width(), height = pool.height();
  const auto map = [&](const float* p) { return cv::Mat(height, width, CV_32F, const_cast<float*>(p)); };
  const cv::Mat smooth = map(smooth_px), slope_x = map(slope_x_px), slope_y = map(slope_y_px), valid = map(valid_px);
  cv::Mat beside_x = map(beside_x_px), beside_y = map(beside_y_px);
  slope_x.copyTo(beside_x);
  slope_y.copyTo(beside_y);
  if (share <= 0.0) return;
  // The Laplacian (the slope's divergence) at the valid points, 0 in the holes; the ridge where its local mean over
  // the ridge's scale departs from 0 by more than kRidgeCut times its typical size (FindRidge).
  cv::Mat laplacian = pool.Map();
  pool.Pass([&](int r0, int r1) {
    cv::Mat dx, dy, l = laplacian.rowRange(r0, r1);  // the filters read the rows beyond the stripe from the map
    cv::Sobel(slope_x.rowRange(r0, r1), dx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::Sobel(slope_y.rowRange(r0, r1), dy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0.0, cv::BORDER_REFLECT);
    cv::add(dx, dy, l);
    cv::multiply(l, valid.rowRange(r0, r1), l);
  });
  cv::Mat ridge_free(height, width, CV_8U);  // 0 on the ridge
  {
    const Ridge ridge = FindRidge(laplacian, valid, cv::Mat(), pool);
    pool.Pass([&](int r0, int r1) {
      for (int r = r0; r < r1; ++r) {
        unsigned char* f = ridge_free.ptr<unsigned char>(r);
        const float *m = ridge.square.ptr<float>(r), *v = valid.ptr<float>(r);
        for (int col = 0; col < width; ++col) f[col] = v[col] > 0.0f && m[col] > ridge.cut ? 0 : 1;
      }
    });
  }
  laplacian.release();
  cv::Mat distance = pool.Map();  // from the ridge (px)
  cv::distanceTransform(ridge_free, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  // The valid points beyond the ridge's reach (0 in `beyond`), in the order distanceTransform labels them (row by
  // row), and for every point the label of the nearest one.
  cv::Mat beyond(height, width, CV_8U);
  std::vector<int> beyond_index{-1};  // label -> the point's index; labels start at 1
  for (int r = 0; r < height; ++r) {
    unsigned char* b = beyond.ptr<unsigned char>(r);
    const float *d = distance.ptr<float>(r), *v = valid.ptr<float>(r);
    for (int col = 0; col < width; ++col) {
      b[col] = d[col] > kRidgeReachPx && v[col] > 0.0f ? 0 : 1;
      if (b[col] == 0) beyond_index.push_back(r * width + col);
    }
  }
  if (beyond_index.size() == 1) return;  // no point beyond the ridge's reach (or no ridge point left nothing within)
  cv::Mat nearest_distance, labels;
  cv::distanceTransform(beyond, nearest_distance, labels, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
  const float tolerance = float(kOwnSideSteps * step_mm);
  pool.Pass([&](int r0, int r1) {
    for (int r = r0; r < r1; ++r) {
      const float *d = distance.ptr<float>(r), *s = smooth.ptr<float>(r);
      const int* label = labels.ptr<int>(r);
      float *gx = beside_x.ptr<float>(r), *gy = beside_y.ptr<float>(r);
      for (int col = 0; col < width; ++col) {
        if (d[col] > kRidgeReachPx) continue;
        const int q = beyond_index[std::size_t(label[col])], qr = q / width, qc = q % width;
        const float qx = slope_x.ptr<float>(qr)[qc], qy = slope_y.ptr<float>(qr)[qc];
        const float extended = smooth.ptr<float>(qr)[qc] + qx * float(col - qc) + qy * float(r - qr);
        if (!(std::abs(extended - s[col]) <= tolerance)) continue;  // not the pixel's own side
        gx[col] += float(share) * (qx - gx[col]);
        gy[col] += float(share) * (qy - gy[col]);
      }
    }
  });
}

}  // namespace fvm::imaging
