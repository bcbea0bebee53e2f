#include "imaging/io/focus_stack_files.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <set>
#include <string>
#include <system_error>

#include <opencv2/core.hpp>

#include "core/input_error.h"
#include "imaging/focus_stack_curves.h"  // kFocusBatch

namespace fvm::imaging {
namespace {

bool IsList(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".csv" || ext == ".txt";
}

bool IsImage(const std::filesystem::path& path) {
  static const std::set<std::string> kImages = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".exr"};
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return kImages.count(ext) > 0;
}

// The mean of the channels, as float.
StackImage GreyOf(const StackImage& colour) {
  StackImage grey;
  grey.width = colour.width;
  grey.height = colour.height;
  const std::size_t n = std::size_t(colour.width) * std::size_t(colour.height);
  const std::size_t channels = std::size_t(colour.channels);
  std::vector<float> pixels(n);
  std::visit(
      [&](const auto& v) {
        for (std::size_t i = 0; i < n; ++i) {
          float sum = 0.0f;
          for (std::size_t c = 0; c < channels; ++c) sum += static_cast<float>(v[i * channels + c]);
          pixels[i] = sum / static_cast<float>(channels);
        }
      },
      colour.pixels);
  grey.pixels = std::move(pixels);
  return grey;
}

}  // namespace

std::vector<FocusStackEntry> ResolveFocusStack(const std::vector<std::filesystem::path>& inputs,
                                               std::optional<double> step_mm) {
  if (inputs.empty()) throw InputError("no focus stack given");
  if (inputs.size() == 1 && IsList(inputs[0])) {
    if (step_mm) {
      throw InputError(inputs[0].string() + ": the list gives each image's z; --z-step-mm is for images named "
                       "directly or a directory");
    }
    return ReadFocusStackList(inputs[0]);
  }
  std::vector<std::filesystem::path> files;
  std::error_code error;
  if (inputs.size() == 1 && std::filesystem::is_directory(inputs[0], error)) {
    for (const auto& item : std::filesystem::directory_iterator(inputs[0], error)) {
      if (item.is_regular_file() && IsImage(item.path())) files.push_back(item.path());
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) throw InputError(inputs[0].string() + ": no image files (.png, .jpg, .tif, ...) in it");
  } else {
    files = inputs;
  }
  try {
    return FocusStackFromImages(files, step_mm.value_or(1.0));
  } catch (const InputError& e) {
    throw InputError(inputs[0].string() + (inputs.size() > 1 ? " ...: " : ": ") + e.what());
  }
}

FocusStackFilesResult ReconstructFocusStackFiles(const std::vector<FocusStackEntry>& entries,
                                                 const FocusStackFilesOptions& options,
                                                 const std::function<void()>& on_image) {
  FocusStackFilesResult out;
  FocusAccumulator accumulator(options.focus);
  FocusStackAligner aligner;
  // The files are decoded a batch at a time on OpenCV's thread pool (decoding one after the other left a core
  // idle for most of a file stack's time); aligning and folding them stays in focus order. A decoding error is
  // kept with its image and thrown when the image's turn comes, so that the first bad file in order is named.
  struct Decoded {
    StackImage grey, colour;
    std::exception_ptr error;
  };
  std::vector<Decoded> batch(kFocusBatch);
  for (std::size_t k0 = 0; k0 < entries.size(); k0 += batch.size()) {
    const std::size_t k1 = std::min(entries.size(), k0 + batch.size());
    cv::parallel_for_(cv::Range(0, int(k1 - k0)), [&](const cv::Range& range) {
      for (int j = range.start; j < range.end; ++j) {
        Decoded& d = batch[std::size_t(j)];
        d = Decoded{};
        try {
          // One decode per file: with colour, the grey image is its channels' mean.
          const std::filesystem::path& file = entries[k0 + std::size_t(j)].file;
          if (options.colour) d.colour = ReadStackColour(file);
          d.grey = options.colour ? GreyOf(d.colour) : ReadStackImage(file);
        } catch (...) {
          d.error = std::current_exception();
        }
      }
    });
    for (std::size_t k = k0; k < k1; ++k) {
      const FocusStackEntry& entry = entries[k];
      Decoded& d = batch[k - k0];
      // A list's images are named by the list's line (and the file), as the user wrote them.
      const std::string line = entry.list.empty() ? "" : entry.list.string() + ":" + std::to_string(entry.line);
      const std::string where = line.empty() ? entry.file.string() : line + " (" + entry.file.string() + ")";
      try {
        if (d.error) std::rethrow_exception(d.error);
        StackImage& colour = d.colour;
        StackImage& grey = d.grey;
        if (k == 0) {
          const StackImage& texture = options.colour ? colour : grey;
          out.eight_bit = std::holds_alternative<std::vector<std::uint8_t>>(texture.pixels);
        }
        if (options.align) {
          const FrameTransform from_first = aligner.Register(grey.View());
          out.alignment.push_back(from_first);
          if (k > 0) {
            grey = FocusStackAligner::Warp(grey.View(), from_first);
            if (options.colour) colour = FocusStackAligner::Warp(colour.View(), from_first);
          }
        }
        const StackImageView colour_view = colour.View();
        accumulator.Add(grey.View(), entry.z_mm, where, options.colour ? &colour_view : nullptr);
      } catch (const InputError& e) {
        const std::string message = e.what();
        if (!line.empty() && message.rfind(where, 0) != 0) throw InputError(line + ": " + message);
        throw;
      }
      if (on_image) on_image();
    }
  }
  out.unregistered = aligner.unregistered();
  out.focus = accumulator.Finish();
  return out;
}

StackImage AllInFocusImage(const FocusResult& result, bool eight_bit) {
  StackImage image;
  image.width = result.height.size_x;
  image.height = result.height.size_y;
  image.channels = result.texture_channels;
  if (eight_bit) {
    std::vector<std::uint8_t> pixels(result.texture.size());
    std::transform(result.texture.begin(), result.texture.end(), pixels.begin(),
                   [](float v) { return std::uint8_t(std::clamp(std::lround(v), 0L, 255L)); });
    image.pixels = std::move(pixels);
  } else {
    // 16-bit grey images hold 0..65535 already; float colour reads come in 0..1.
    float top = 0.0f;
    for (float v : result.texture) top = std::max(top, v);
    const float scale = top <= 1.0f ? 65535.0f : 1.0f;
    std::vector<std::uint16_t> pixels(result.texture.size());
    std::transform(result.texture.begin(), result.texture.end(), pixels.begin(),
                   [scale](float v) { return std::uint16_t(std::clamp(std::lround(v * scale), 0L, 65535L)); });
    image.pixels = std::move(pixels);
  }
  return image;
}

}  // namespace fvm::imaging
