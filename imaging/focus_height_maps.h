#pragma once
// The maps of a reconstructed height map that focus variation's corrections and uncertainty model read
// (focus_variation.cc): its slope, its scatter about the local mean, its roughness at the window's scale and its
// curvature, each a named map from the pool (focus_map_pool.h). Internal to imaging/ (OpenCV types); used by
// focus_variation.cc only.

#include <opencv2/core.hpp>

#include <cmath>
#include <vector>

#include "imaging/focus_map_pool.h"

namespace fvm::imaging {

// The variance of a Gaussian variable whose squares' median is that of `square`'s points of positive `weight` (a
// sample of them): the median of chi^2 with 1 degree of freedom is 0.4549 times the variance. A robust scale, as a
// redescending M-estimator leaves out outliers (Huber 1981).
float TypicalSquare(const cv::Mat& square, const cv::Mat& weight);

// Rows r0..r1 of `mean`: the Gaussian blur of `numerator` over that of `weights` (`total` is scratch), the local
// mean a weighted average takes where `numerator` holds the values times their weights (rows of a stripe, blurred
// with the rows beyond it as OpenCV's filters read a region of interest).
void BlurredRatio(const cv::Mat& numerator, const cv::Mat& weights, double sigma_px, int r0, int r1, cv::Mat& total,
                  cv::Mat& mean);

// The local mean of `values` weighted by `weights` over a Gaussian of sigma_px: the blur of values x weights over
// the blur of the weights. The product is complete before any band blurs it, since a band's blur reads the rows
// beside it.
cv::Mat WeightedLocalMean(const cv::Mat& values, const cv::Mat& weights, double sigma_px, MapPool& pool);

// The local slope (height change per pixel along x and y, mm) of a map with holes, from its smooth local mean.
struct Slope {
  cv::Mat x, y;
  float Magnitude(int r, int col) const { return std::hypot(x.ptr<float>(r)[col], y.ptr<float>(r)[col]); }
};

// A height map with holes as float maps for the filters, its smooth local mean (a Gaussian of 2 px over the valid
// points only) and that mean's slope.
struct SmoothedHeights {
  cv::Mat heights;  // mm, relative to the origin (so that float keeps the nm of a stage tens of mm out); 0 in holes
  cv::Mat valid;    // 1 at the valid points, 0 in the holes
  cv::Mat share;    // the Gaussian's weight on the valid points around each point (1 where all are valid)
  cv::Mat smooth;   // the local mean of the valid points' heights
  Slope slope;      // of `smooth`
};
SmoothedHeights SmoothHeights(const std::vector<double>& z, double origin, MapPool& pool);

// The rms of the heights about their smooth local mean, over a window around each valid point.
cv::Mat LocalScatter(const SmoothedHeights& smoothed, MapPool& pool);

// The heights' roughness at the window's scale (see focus_height_maps.cc), and what it finds on the way: the
// surface's own curvature, the Laplacian (mm per px^2) of the heights smoothed over 2 px, its weighted local mean over
// 14 px with the sharp bends (a calotte's rim) and their ridge left out; NaN within reach of them
// (focus_surface_curvature.h). And the same filled where NaN by the local mean of the known values over 12 px (NaN
// where none lies within reach).
struct WindowScaleMaps {
  cv::Mat roughness, curvature, filled_curvature;
};
// From the smoothed heights, whose maps it lets go of as it is done with them (the caller passes them on with
// std::move, so that their memory serves the roughness's own maps).
WindowScaleMaps WindowScaleRoughness(SmoothedHeights smoothed, MapPool& pool);

}  // namespace fvm::imaging
