#pragma once
// The maps of a reconstructed height map that focus variation's uncertainty model reads (focus_variation.cc): its
// slope, its scatter about the local mean and its roughness at the window's scale. Internal to imaging/ (OpenCV
// types); used by focus_variation.cc only.

#include <opencv2/core.hpp>

#include <cmath>
#include <functional>
#include <vector>

#include "imaging/focus_stack_curves.h"

namespace fvm::imaging {

// Float maps of the height map's size over memory in huge pages, reused from map to map: fresh 4 kB pages cost
// more than the filters that fill them (a page fault per 4 kB on a virtual machine). The maps are filled and
// filtered in stripes of rows in parallel (ForStripes): a filter applied to a stripe of a map reads the rows
// beyond it from the map itself (OpenCV filters a sub-matrix with its real neighbours unless told
// BORDER_ISOLATED), so each stripe's result is that of the whole map's filter.
struct MapBuffers {
  int width = 0, height = 0;
  bool parallel = true;
  HugeVector<float> storage[16];

  cv::Mat operator[](int i) {
    HugeVector<float>& v = storage[i];
    v.resize(std::size_t(width) * std::size_t(height));  // left uninitialised: each pass writes all of it
    return cv::Mat(height, width, CV_32F, v.data());
  }
  // body(r0, r1) for each stripe of rows; every stripe of a pass ends before the next pass starts.
  void Pass(const std::function<void(int, int)>& body, int stripe_rows = kStripeRows) const {
    ForStripes(height, parallel, body, stripe_rows);
  }
};

// The variance of a Gaussian variable whose squares' median is that of `square`'s points of positive `weight` (a
// sample of them): the median of chi^2 with 1 degree of freedom is 0.4549 times the variance. A robust scale, as a
// redescending M-estimator leaves out outliers (Huber 1981).
float TypicalSquare(const cv::Mat& square, const cv::Mat& weight);

// Rows r0..r1 of `mean`: the Gaussian blur of `numerator` over that of `weights` (`total` is scratch), the local
// mean a weighted average takes where `numerator` holds the values times their weights (rows of a stripe, blurred
// with the rows beyond it as OpenCV's filters read a region of interest).
void BlurredRatio(const cv::Mat& numerator, const cv::Mat& weights, double sigma_px, int r0, int r1, cv::Mat& total,
                  cv::Mat& mean);

// The local slope (height change per pixel along x and y, mm) of a map with holes, from its smooth local mean
// (in buffers 4 and 6, which the scatter below leaves alone).
struct Slope {
  cv::Mat x, y;
  float Magnitude(int r, int col) const { return std::hypot(x.ptr<float>(r)[col], y.ptr<float>(r)[col]); }
};
Slope SlopePerPixel(const std::vector<double>& z, double origin, MapBuffers& buffers);

// The rms of the heights about their smooth local mean, over a window around each valid point (buffer 5).
cv::Mat LocalScatter(const std::vector<double>& z, double origin, MapBuffers& buffers);

// The heights' roughness at the window's scale (buffer 3), from what SlopePerPixel leaves in the buffers and the
// slope of the same heights (see focus_height_maps.cc). Leaves in buffer 11 the surface's own curvature: the
// Laplacian (mm per px^2) of the heights smoothed over 2 px, its weighted local mean over 14 px with the sharp bends
// (a calotte's rim) and their ridge left out; NaN within reach of them (focus_surface_curvature.h). And in buffer 15
// the same filled where NaN by the local mean of the known values over 12 px (NaN where none lies within reach).
cv::Mat WindowScaleRoughness(const Slope& slope, MapBuffers& buffers);

}  // namespace fvm::imaging
