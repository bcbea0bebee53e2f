#pragma once
// The images of a focus stack: one grey channel (or, for the all-in-focus image, 3 colour channels interleaved),
// row-major, 8 or 16 bit or float, as cameras and image files hold them. Kept in their own type so that a
// 1024 x 1024 x 100 stack of 8-bit images stays 100 MB, not 400.

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <variant>
#include <vector>

namespace fvm::imaging {

// A grey image that the caller owns; focus variation only reads it.
struct StackImageView {
  int width = 0;
  int height = 0;
  std::variant<std::span<const std::uint8_t>, std::span<const std::uint16_t>, std::span<const float>> pixels;
  int channels = 1;  // interleaved
};

// A grey image that owns its pixels.
struct StackImage {
  int width = 0;
  int height = 0;
  std::variant<std::vector<std::uint8_t>, std::vector<std::uint16_t>, std::vector<float>> pixels;
  int channels = 1;  // interleaved

  StackImageView View() const {
    return {width, height,
            std::visit([](const auto& v) -> decltype(StackImageView::pixels) { return std::span(v.data(), v.size()); },
                       pixels),
            channels};
  }
};

// Copies a view's pixels into `image`, reusing its memory when the size and type repeat (a stack's images are
// copied into the same few buffers, not into fresh pages each time).
inline void CopyInto(const StackImageView& view, StackImage& image) {
  image.width = view.width;
  image.height = view.height;
  image.channels = view.channels;
  std::visit(
      [&](auto span) {
        using T = std::remove_const_t<typename decltype(span)::element_type>;
        if (!std::holds_alternative<std::vector<T>>(image.pixels)) image.pixels = std::vector<T>();
        std::get<std::vector<T>>(image.pixels).assign(span.begin(), span.end());
      },
      view.pixels);
}

}  // namespace fvm::imaging
