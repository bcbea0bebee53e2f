#include "artefacts/simulation/focus_stack_render.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace fvm::artefacts {
namespace {

template <typename T>
std::vector<T> Quantise(const std::vector<float>& grey) {
  std::vector<T> out(grey.size());
  if constexpr (std::is_same_v<T, float>) {
    std::copy(grey.begin(), grey.end(), out.begin());
  } else {
    constexpr float kMax = static_cast<float>(std::numeric_limits<T>::max());
    for (std::size_t i = 0; i < grey.size(); ++i) out[i] = static_cast<T>(std::clamp(std::lround(grey[i]), 0L, long(kMax)));
  }
  return out;
}

}  // namespace

void FocusStackRenderOptions::Check() const {
  if (z_mm.empty()) throw std::invalid_argument("focus stack: no z positions");
  for (double z : z_mm) {
    if (!std::isfinite(z)) throw std::invalid_argument("focus stack: z positions must be finite");
  }
  if (!(sigma_px_per_mm > 0.0) || !(max_sigma_px > 0.0) || blur_levels < 2 || !(texture_sigma_px >= 0.0) ||
      !(focus_sigma_px >= 0.0) || !(focus_sigma_px < max_sigma_px)) {
    throw std::invalid_argument("focus stack: blur rate and maximum > 0, at least 2 levels, texture sigma >= 0, "
                                "focus sigma from 0 to below the maximum");
  }
  if (!(contrast > 0.0) || !(noise >= 0.0) || !std::isfinite(level) || !(electrons_per_count >= 0.0)) {
    throw std::invalid_argument("focus stack: contrast > 0, noise >= 0, electrons per count >= 0, finite level");
  }
}

std::vector<imaging::StackImageView> RenderedFocusStack::Views() const {
  std::vector<imaging::StackImageView> views;
  views.reserve(images.size());
  for (const imaging::StackImage& image : images) views.push_back(image.View());
  return views;
}

RenderedFocusStack RenderFocusStack(const imaging::HeightMap& surface, const FocusStackRenderOptions& options) {
  options.Check();
  const int w = surface.size_x, h = surface.size_y;
  if (w < 1 || h < 1 || surface.z_mm.size() != std::size_t(w) * std::size_t(h)) {
    throw std::invalid_argument("focus stack: the surface map is empty or inconsistent");
  }
  // The texture: white noise smoothed to the grain, scaled to unit standard deviation.
  cv::Mat texture(h, w, CV_32F);
  {
    std::mt19937_64 random(options.seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    for (int y = 0; y < h; ++y) {
      float* row = texture.ptr<float>(y);
      for (int x = 0; x < w; ++x) row[x] = normal(random);
    }
    if (options.texture_sigma_px > 0.0) {
      cv::GaussianBlur(texture, texture, cv::Size(), options.texture_sigma_px, 0.0, cv::BORDER_REFLECT);
    }
    cv::Scalar mean, deviation;
    cv::meanStdDev(texture, mean, deviation);
    texture = (texture - mean[0]) / deviation[0];
  }
  // The texture at every blur level; level l has sigma l * level_step.
  const int levels = options.blur_levels;
  const double level_step = options.max_sigma_px / (levels - 1);
  std::vector<cv::Mat> blurred(static_cast<std::size_t>(levels));
  blurred[0] = texture;
  cv::parallel_for_(cv::Range(1, levels), [&](const cv::Range& range) {
    for (int l = range.start; l < range.end; ++l) {
      cv::GaussianBlur(texture, blurred[std::size_t(l)], cv::Size(), l * level_step, 0.0, cv::BORDER_REFLECT);
    }
  });

  RenderedFocusStack stack;
  stack.z_mm = options.z_mm;
  const int n = static_cast<int>(options.z_mm.size());
  stack.images.resize(std::size_t(n));
  // One image per task, each with its own seed: the same bytes whatever the number of threads.
  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      std::seed_seq seeds{options.seed, std::uint64_t(k) + 1};
      std::mt19937_64 random(seeds);
      std::normal_distribution<float> normal(0.0f, 1.0f);
      const double z = options.z_mm[std::size_t(k)];
      std::vector<float> grey(std::size_t(w) * std::size_t(h));
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float height = surface.at(x, y);
          const double sigma = std::isfinite(height)
                                   ? std::hypot(options.focus_sigma_px, (z - height) * options.sigma_px_per_mm)
                                   : options.max_sigma_px;
          const double position = std::min(sigma / level_step, double(levels - 1));
          const int l = std::min(static_cast<int>(position), levels - 2);
          const float t = static_cast<float>(position - l);
          const float value = (1.0f - t) * blurred[std::size_t(l)].at<float>(y, x) +
                              t * blurred[std::size_t(l) + 1].at<float>(y, x);
          const double signal = options.level + options.contrast * value;
          // Poisson noise of the photo-electrons, Gaussian at these counts (hundreds of electrons and more).
          const double shot = options.electrons_per_count > 0.0
                                  ? std::sqrt(std::max(signal, 0.0) / options.electrons_per_count) : 0.0;
          grey[std::size_t(y) * std::size_t(w) + std::size_t(x)] =
              static_cast<float>(signal + std::hypot(options.noise, shot) * normal(random));
        }
      }
      imaging::StackImage& image = stack.images[std::size_t(k)];
      image.width = w;
      image.height = h;
      switch (options.type) {
        case StackPixelType::kUint8:
          image.pixels = Quantise<std::uint8_t>(grey);
          break;
        case StackPixelType::kUint16:
          image.pixels = Quantise<std::uint16_t>(grey);
          break;
        case StackPixelType::kFloat32:
          image.pixels = std::move(grey);
          break;
      }
    }
  });
  return stack;
}

double BlurRateForAperture(double na, double pixel_mm) {
  if (!(na > 0.0 && na < 1.0) || !(pixel_mm > 0.0)) {
    throw std::invalid_argument("focus stack: numerical aperture in (0, 1) and a positive pixel size");
  }
  return 0.5 * std::tan(std::asin(na)) / pixel_mm;
}

std::vector<double> EvenZSteps(double z_first_mm, double step_mm, int count) {
  std::vector<double> z(static_cast<std::size_t>(std::max(count, 0)));
  for (int k = 0; k < count; ++k) z[std::size_t(k)] = z_first_mm + k * step_mm;
  return z;
}

imaging::HeightMap TiltedPlane(int size_x, int size_y, double pixel_mm, double z0_mm, double slope_x,
                               double slope_y) {
  imaging::HeightMap map;
  map.size_x = size_x;
  map.size_y = size_y;
  map.dx_mm = map.dy_mm = pixel_mm;
  map.z_mm.resize(std::size_t(size_x) * std::size_t(size_y));
  for (int y = 0; y < size_y; ++y) {
    for (int x = 0; x < size_x; ++x) {
      map.at(x, y) = static_cast<float>(z0_mm + slope_x * x * pixel_mm + slope_y * y * pixel_mm);
    }
  }
  map.source = "tilted plane";
  return map;
}

}  // namespace fvm::artefacts
