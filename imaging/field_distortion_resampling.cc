// Tiles resampled through a field distortion (field_distortion.h), with OpenCV's remap: the part of the field that
// needs OpenCV, so that the model itself stays in fvm_imaging and the fvm executable reaches this through the OpenCV
// plugin (opencv_imaging.h). Undistorted tiles are registered again, to the thousandth of a pixel, so they are
// resampled with Lanczos-4, as the registration resamples (subpixel_refinement.cc): OpenCV's cubic (a = -0.75) moves
// what it resamples by an amount that depends on the fraction, and on scangen's pairs (k1 = 2 and 3 px) the steps
// registered on cubic-undistorted tiles missed the truth by -0.0037 and +0.0003 px, on Lanczos-undistorted ones by
// +0.0002 and +0.0001 (+-0.0003), as the raw tiles' own registration does without a field.

#include <algorithm>
#include <limits>
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "imaging/field_distortion.h"

namespace fvm::imaging {
namespace {

cv::Mat AsMat(const TileImage& image) {
  return cv::Mat(static_cast<int>(image.rows()), static_cast<int>(image.cols()), CV_32F,
                 const_cast<float*>(image.data()));
}

TileImage Remapped(const TileImage& source, const cv::Mat& map_x, const cv::Mat& map_y, bool outside_nan,
                   int interpolation) {
  TileImage out(map_x.rows, map_x.cols);
  cv::Mat dst(map_x.rows, map_x.cols, CV_32F, out.data());
  if (outside_nan) {
    // The kernel's reach past the edge, for a point inside the tile, reads the edge pixel; the points outside are
    // the caller's to mark. (A NaN border made a ring of invalid pixels 1-2 px wide along every edge, even where
    // the field moves nothing, and the registration of undistorted tiles, on scangen's pairs with a zero field,
    // scattered by 0.013 px a step against 0.0017 px on the raw tiles, and missed by -0.007 px on average.)
    cv::remap(AsMat(source), dst, map_x, map_y, interpolation, cv::BORDER_REPLICATE);
  } else {
    // remap takes its border value for a point wholly outside, whatever the border mode: the nearest edge pixel
    // is the point clamped onto the tile.
    cv::Mat x, y;
    cv::min(cv::max(map_x, 0.0), source.cols() - 1.0, x);
    cv::min(cv::max(map_y, 0.0), source.rows() - 1.0, y);
    cv::remap(AsMat(source), dst, x, y, interpolation, cv::BORDER_REPLICATE);
  }
  return out;
}

// Where each undistorted pixel is seen in the raw tile (FieldDistortion::RawPixel), solved on a grid of every 8th
// pixel, interpolated bilinearly between, and taken one fixed-point step further at every pixel: the fixed-point
// solve at every pixel cost more than the resampling, and the interpolation alone errs by the field's curvature
// over 8 px, under 1e-3 px (h^2 / 8 times the second derivative) but with one sign on each side of the tile's centre:
// on average h^2 / 12 times the Laplacian, +-0.0005 px in the bands of a 20 % overlap of 512 px tiles per px of
// radial field, so that a pair registered on undistorted tiles stepped 0.001 px (2.4 ppm) per px too short or long.
// One step u = u' - d(u) from there leaves the error times the field's gradient (a few hundredths).
void UndistortionMap(const FieldDistortion& field, int w, int h, cv::Mat& map_x, cv::Mat& map_y) {
  constexpr int kStep = 8;
  map_x.create(h, w, CV_32F), map_y.create(h, w, CV_32F);
  if (w < 2 || h < 2) {  // no grid to interpolate on
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const Eigen::Vector2d u = field.RawPixel(Eigen::Vector2d(x, y));
        map_x.at<float>(y, x) = static_cast<float>(u.x()), map_y.at<float>(y, x) = static_cast<float>(u.y());
      }
    }
    return;
  }
  const int nx = (w - 1 + kStep - 1) / kStep + 1, ny = (h - 1 + kStep - 1) / kStep + 1;
  std::vector<Eigen::Vector2d> knots(static_cast<size_t>(nx * ny));
  const auto knot_x = [&](int i) { return std::min(i * kStep, w - 1); };
  const auto knot_y = [&](int j) { return std::min(j * kStep, h - 1); };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) knots[static_cast<size_t>(j * nx + i)] = field.RawPixel(Eigen::Vector2d(knot_x(i), knot_y(j)));
  }
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const int j = std::min(y / kStep, ny - 2);
      const double fy = static_cast<double>(y - knot_y(j)) / (knot_y(j + 1) - knot_y(j));
      for (int x = 0; x < w; ++x) {
        const int i = std::min(x / kStep, nx - 2);
        const double fx = static_cast<double>(x - knot_x(i)) / (knot_x(i + 1) - knot_x(i));
        const auto at = [&](int di, int dj) { return knots[static_cast<size_t>((j + dj) * nx + i + di)]; };
        // The displacement (raw less undistorted) interpolated, so that the map is exact wherever the field is 0.
        const auto shift = [&](int di, int dj) {
          return Eigen::Vector2d(at(di, dj) - Eigen::Vector2d(knot_x(i + di), knot_y(j + dj)));
        };
        const Eigen::Vector2d s = (1 - fy) * ((1 - fx) * shift(0, 0) + fx * shift(1, 0)) +
                                  fy * ((1 - fx) * shift(0, 1) + fx * shift(1, 1));
        const Eigen::Vector2d undistorted(x, y);
        const Eigen::Vector2d raw = undistorted - field.Displacement(undistorted + s);
        map_x.at<float>(y, x) = static_cast<float>(raw.x());
        map_y.at<float>(y, x) = static_cast<float>(raw.y());
      }
    }
  });
}

}  // namespace

std::vector<TileImage> UndistortTiles(const std::vector<TileImage>& raw, const FieldDistortion& field,
                                      bool outside_nan) {
  if (field.Identity() || raw.empty()) return raw;
  field.Check();
  const int w = static_cast<int>(raw.front().cols()), h = static_cast<int>(raw.front().rows());
  for (const TileImage& tile : raw) {
    if (tile.cols() != field.width_px || tile.rows() != field.height_px) {
      throw std::invalid_argument("UndistortTiles: the field is for " + std::to_string(field.width_px) + " x " +
                                  std::to_string(field.height_px) + " px tiles, a tile is " +
                                  std::to_string(tile.cols()) + " x " + std::to_string(tile.rows()));
    }
  }
  cv::Mat map_x, map_y;
  UndistortionMap(field, w, h, map_x, map_y);
  std::vector<TileImage> out(raw.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(raw.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      TileImage& tile = out[static_cast<size_t>(i)];
      tile = Remapped(raw[static_cast<size_t>(i)], map_x, map_y, outside_nan, cv::INTER_LANCZOS4);
      if (!outside_nan) continue;
      // Outside the raw tile is no measurement: invalid, not the border's value.
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float ux = map_x.at<float>(y, x), uy = map_y.at<float>(y, x);
          if (ux < 0.0f || uy < 0.0f || ux > w - 1.0f || uy > h - 1.0f) tile(y, x) = std::numeric_limits<float>::quiet_NaN();
        }
      }
    }
  });
  return out;
}

TileImage UndistortTile(const TileImage& raw, const FieldDistortion& field, bool outside_nan) {
  return UndistortTiles({raw}, field, outside_nan).front();
}

TileImage DistortTile(const TileImage& ideal_with_margin, int margin_px, const FieldDistortion& field) {
  const int w = static_cast<int>(ideal_with_margin.cols()) - 2 * margin_px;
  const int h = static_cast<int>(ideal_with_margin.rows()) - 2 * margin_px;
  if (w <= 0 || h <= 0) throw std::invalid_argument("DistortTile: the margin leaves no tile");
  if (field.LargestDisplacementPx() + 4.5 > margin_px) {
    throw std::invalid_argument("DistortTile: a margin of " + std::to_string(margin_px) +
                                " px does not cover the field's largest displacement and Lanczos-4's reach");
  }
  // A camera pixel records the mean over its area of what the field sends it, not one point: 3 x 3 points a pixel,
  // each read by Lanczos-4. One point a pixel through OpenCV's cubic (a = -0.75) shifted what a pixel shows by a few
  // hundredths of a pixel with the fraction of d(u), the same in every tile, so every overlap of one direction shared
  // it: a stretch of the simulated mosaic and a block scatter (2.1 on the 3 x 3 test grid) that was the renderer's.
  constexpr int kPoints = 3;
  TileImage sum = TileImage::Zero(h, w);
  cv::Mat map_x(h, w, CV_32F), map_y(h, w, CV_32F);
  for (int j = 0; j < kPoints; ++j) {
    for (int i = 0; i < kPoints; ++i) {
      const Eigen::Vector2d sub((i + 0.5) / kPoints - 0.5, (j + 0.5) / kPoints - 0.5);
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const Eigen::Vector2d point = Eigen::Vector2d(x, y) + sub;
          const Eigen::Vector2d at = point + field.Displacement(point);
          map_x.at<float>(y, x) = static_cast<float>(at.x() + margin_px);
          map_y.at<float>(y, x) = static_cast<float>(at.y() + margin_px);
        }
      }
      sum += Remapped(ideal_with_margin, map_x, map_y, false, cv::INTER_LANCZOS4);
    }
  }
  return sum / static_cast<float>(kPoints * kPoints);
}

}  // namespace fvm::imaging
