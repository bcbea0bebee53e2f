#pragma once
// A focus stack from its files to a height map: the stack named as a CSV list `file,z_mm`, a directory of images
// or the image files themselves (z then from a step, or the image's index: heights in slice units); each image
// read, optionally aligned to the first (a breathing lens), and reduced; the all-in-focus image in colour when the
// files are.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "imaging/focus_stack_alignment.h"
#include "imaging/focus_variation.h"
#include "imaging/io/focus_stack_io.h"

namespace fvm::imaging {

// `inputs`: one .csv list; or one directory (its image files by name); or 3 or more image files in focus order.
// Without a list, z_mm[i] = i * step_mm, and step_mm 1 when not given (heights in slice units). Throws InputError
// naming the input for an empty directory, a missing file, a list given with a step, fewer than 3 images.
std::vector<FocusStackEntry> ResolveFocusStack(const std::vector<std::filesystem::path>& inputs,
                                               std::optional<double> step_mm);

struct FocusStackFilesOptions {
  FocusVariationOptions focus;
  bool align = false;    // register every image to the first (enhanced correlation, affine)
  bool colour = false;   // make the all-in-focus image of the files' colour channels (read a second time)
};

struct FocusStackFilesResult {
  FocusResult focus;
  std::vector<FrameTransform> alignment;  // per image, when aligned: the first image's pixels in this one
  int unregistered = 0;                   // images aligned as their neighbour (no common sharp texture)
  bool eight_bit = true;                  // the images (so the all-in-focus image) are 8-bit
};

// `on_image` is called after each image (progress). Errors name the list line or the file.
FocusStackFilesResult ReconstructFocusStackFiles(const std::vector<FocusStackEntry>& entries,
                                                 const FocusStackFilesOptions& options,
                                                 const std::function<void()>& on_image = {});

// The all-in-focus image as a file holds it: 8-bit when the images were, else 16-bit (float 0..1 scaled).
StackImage AllInFocusImage(const FocusResult& result, bool eight_bit);

}  // namespace fvm::imaging
