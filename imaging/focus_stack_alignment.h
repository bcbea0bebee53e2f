#pragma once
// Aligning the images of a focus stack taken through a lens that breathes: as the focus moves, a macro lens
// changes its magnification slightly and a hand-held or loosely mounted camera shifts, so one point of the
// object wanders over the sensor from image to image. Each image is registered to its neighbour in the stack
// (the pair least different in focus) by the enhanced correlation coefficient [Evangelidis 2008], as an affine
// map (scale, rotation, shift, and the little shear a tilted sensor adds), and the maps are chained back to the
// first image.

#include <array>
#include <vector>

#include "imaging/focus_stack.h"

namespace fvm::imaging {

// Where a pixel (x, y) of the first image lies in this image: x' = a[0] x + a[1] y + a[2],
// y' = a[3] x + a[4] y + a[5] (pixels).
using FrameTransform = std::array<double, 6>;

class FocusStackAligner {
 public:
  // Registers `grey` (one channel) to the previous image given, and returns the map from the first image into
  // this one. The first image gets the identity. Where the registration does not converge (the two images share
  // no sharp texture: both far out of focus, or a texture-free scene) the image keeps the previous one's map and
  // is counted in unregistered(). Throws InputError for an image of another size.
  FrameTransform Register(const StackImageView& grey);
  int unregistered() const { return unregistered_; }

  // The image resampled into the first image's frame (bilinear; pixels outside it repeat the edge).
  static StackImage Warp(const StackImageView& image, const FrameTransform& from_first);

 private:
  std::vector<float> previous_;  // the previous image, grey, at the registration's scale
  int width_ = 0, height_ = 0, count_ = 0, unregistered_ = 0;
  FrameTransform from_first_{1, 0, 0, 0, 1, 0};
};

}  // namespace fvm::imaging
