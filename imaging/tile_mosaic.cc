#include "imaging/tile_mosaic.h"

#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace fvm::imaging {
namespace {

// Tent weights: 1 at the tile's centre, falling to 1 / (n / 2) at its outermost pixels.
cv::Mat FeatherWeights(int width, int height) {
  cv::Mat w(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    const float wy = static_cast<float>(std::min(y + 1, height - y)) / static_cast<float>((height + 1) / 2);
    for (int x = 0; x < width; ++x) {
      const float wx = static_cast<float>(std::min(x + 1, width - x)) / static_cast<float>((width + 1) / 2);
      w.at<float>(y, x) = wx * wy;
    }
  }
  return w;
}

}  // namespace

Mosaic FuseTiles(const std::vector<TileImage>& tiles, const std::vector<Eigen::Vector2d>& positions_px,
                 const std::function<void(int done, int total)>& on_tile_fused) {
  if (tiles.empty() || tiles.size() != positions_px.size()) {
    throw std::invalid_argument("FuseTiles: one position per tile, and at least one tile");
  }
  Eigen::Vector2d lo = positions_px.front(), hi = lo;
  for (size_t i = 0; i < tiles.size(); ++i) {
    const Eigen::Vector2d& p = positions_px[i];
    if (!p.allFinite()) throw std::invalid_argument("FuseTiles: a tile position is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p + Eigen::Vector2d(static_cast<double>(tiles[i].cols()), static_cast<double>(tiles[i].rows())));
  }
  Mosaic out;
  out.origin_px = lo.array().floor();
  const int width = static_cast<int>(std::ceil(hi.x() - out.origin_px.x())) + 1;
  const int height = static_cast<int>(std::ceil(hi.y() - out.origin_px.y())) + 1;
  // Weighted sums of value and weight: premultiplying before resampling keeps the border's zero weight from
  // ringing into the values.
  cv::Mat sum = cv::Mat::zeros(height, width, CV_32F), weight = cv::Mat::zeros(height, width, CV_32F);
  // Where some tile's valid pixels surround the point entirely (bilinear validity 1): elsewhere the resampling
  // kernel would reach across an invalid pixel and make up a height the instrument never measured.
  cv::Mat covered = cv::Mat::zeros(height, width, CV_32F);
  for (size_t i = 0; i < tiles.size(); ++i) {
    const cv::Mat tile(static_cast<int>(tiles[i].rows()), static_cast<int>(tiles[i].cols()), CV_32F,
                       const_cast<float*>(tiles[i].data()));
    const Eigen::Vector2d at = positions_px[i] - out.origin_px;
    const int ix = static_cast<int>(std::floor(at.x())), iy = static_cast<int>(std::floor(at.y()));
    const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, at.x() - ix, 0, 1, at.y() - iy);
    const cv::Size size(tile.cols + 1, tile.rows + 1);
    // Invalid pixels (NaN) weigh nothing.
    cv::Mat w = FeatherWeights(tile.cols, tile.rows), value = tile.clone(), valid;
    const cv::Mat invalid = tile != tile;
    w.setTo(0.0f, invalid);
    value.setTo(0.0f, invalid);
    cv::Mat(~invalid).convertTo(valid, CV_32F, 1.0 / 255.0);
    cv::Mat moved_value, moved_weight, moved_valid;
    cv::warpAffine(value.mul(w), moved_value, shift, size, cv::INTER_LANCZOS4, cv::BORDER_CONSTANT, 0);
    cv::warpAffine(w, moved_weight, shift, size, cv::INTER_LANCZOS4, cv::BORDER_CONSTANT, 0);
    cv::warpAffine(valid, moved_valid, shift, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    const cv::Rect roi(ix, iy, size.width, size.height);
    sum(roi) += moved_value;
    weight(roi) += moved_weight;
    covered(roi) = cv::max(covered(roi), moved_valid);
    if (on_tile_fused) on_tile_fused(static_cast<int>(i) + 1, static_cast<int>(tiles.size()));
  }
  out.image.resize(height, width);
  // A tile's corner pixel weighs 4 / (w h); a sum below a four-hundredth of that is the resampling kernel's
  // tail beyond the tiles or around an invalid pixel, not a tile's pixel.
  const float floor = 0.01f / static_cast<float>(tiles.front().size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float w = weight.at<float>(y, x);
      const bool measured = w > floor && covered.at<float>(y, x) > 0.999f;
      out.image(y, x) = measured ? sum.at<float>(y, x) / w : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return out;
}

HeightMap MosaicToHeightMap(const Mosaic& mosaic, int tile_width, int tile_height, double pixel_mm,
                            const Eigen::Vector2d& first_centre_mm) {
  HeightMap map;
  map.size_x = static_cast<int>(mosaic.image.cols());
  map.size_y = static_cast<int>(mosaic.image.rows());
  map.dx_mm = map.dy_mm = pixel_mm;
  // Pixel (c, r) of the mosaic lies at origin + (c, r) in the tiles' frame; the first tile's centre pixel at
  // ((w - 1) / 2, (h - 1) / 2). Image rows run to -Y, the map's rows to +Y.
  map.x0_mm = first_centre_mm.x() + (mosaic.origin_px.x() - (tile_width - 1) / 2.0) * pixel_mm;
  map.y0_mm = first_centre_mm.y() - (mosaic.origin_px.y() + map.size_y - 1 - (tile_height - 1) / 2.0) * pixel_mm;
  map.z_mm.resize(static_cast<size_t>(map.size_x) * static_cast<size_t>(map.size_y));
  for (int r = 0; r < map.size_y; ++r) {
    for (int c = 0; c < map.size_x; ++c) map.at(c, map.size_y - 1 - r) = mosaic.image(r, c);
  }
  map.source = "fvm stitch: fused tiles";
  return map;
}

}  // namespace fvm::imaging
