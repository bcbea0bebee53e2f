#pragma once
// Focus stacks rendered from a known surface, for testing and benchmarking focus variation: a random texture on
// the surface, seen through optics whose blur grows with the distance between the focal plane and the surface
// under each pixel, plus sensor noise. The surface is the truth the reconstructed height map is compared with.
//
// The blur is a Gaussian whose sigma grows in proportion to the defocus |z - surface(x, y)| from a floor in focus
// (the waist of a Gaussian beam: sigma^2 = sigma0^2 + (rate dz)^2 [Siegman 1986]); per pixel the image blends
// linearly between a few precomputed blur levels of the texture (exact at the levels, close between).

#include <cstdint>
#include <vector>

#include "imaging/focus_stack.h"
#include "imaging/height_map.h"

namespace fvm::artefacts {

enum class StackPixelType { kUint8, kUint16, kFloat32 };

struct FocusStackRenderOptions {
  std::vector<double> z_mm;         // the focal plane of each image (see EvenZSteps)
  double sigma_px_per_mm = 1000.0;  // blur sigma in px per mm of defocus (here 1 px per um)
  double max_sigma_px = 8.0;        // the blur saturates beyond this: far out of focus is just grey
  // The PSF's sigma in focus, px: diffraction (about 0.21 lambda / NA) and the pixel's own integration. Real
  // optics never image sharper; 0 renders the texture itself in focus.
  double focus_sigma_px = 0.0;
  int blur_levels = 17;             // precomputed blurs from 0 to max_sigma_px
  double texture_sigma_px = 0.7;    // grain of the texture: white noise smoothed by this Gaussian
  // Grey levels in counts (8-bit: 0..255, 16-bit: 0..65535; float: as given): mean, standard deviation of the
  // texture in focus, and sensor noise (Gaussian, independent per pixel and image).
  double level = 128.0;
  double contrast = 40.0;
  double noise = 1.0;                // read noise, counts rms
  // Shot noise: photo-electrons per count (the camera's gain); the grey level g then carries Poisson noise of
  // sqrt(g / electrons_per_count) counts rms on top of the read noise. 0: no shot noise.
  double electrons_per_count = 0.0;
  StackPixelType type = StackPixelType::kUint8;
  std::uint64_t seed = 1;
  void Check() const;  // throws std::invalid_argument
};

struct RenderedFocusStack {
  std::vector<imaging::StackImage> images;
  std::vector<double> z_mm;

  std::vector<imaging::StackImageView> Views() const;
};

// Heights where the surface map is NaN are treated as far out of focus in every image.
RenderedFocusStack RenderFocusStack(const imaging::HeightMap& surface, const FocusStackRenderOptions& options);

// The blur rate (sigma in px per mm of defocus) of optics of numerical aperture na imaging pixel_mm pixels: the
// geometric blur disc of radius |dz| tan(asin(na)) has a sigma of half its radius (a uniform disc of radius r has
// r / 2 rms per axis).
double BlurRateForAperture(double na, double pixel_mm);

// count positions from z_first_mm, step_mm apart.
std::vector<double> EvenZSteps(double z_first_mm, double step_mm, int count);

// A plane z = z0 + slope_x * x + slope_y * y on a size_x x size_y grid of pixel pitch pixel_mm, origin 0.
imaging::HeightMap TiltedPlane(int size_x, int size_y, double pixel_mm, double z0_mm, double slope_x,
                               double slope_y);

}  // namespace fvm::artefacts
