#pragma once
// Focus stacks on disk: a CSV list `file,z_mm` (with `#` comment lines) naming one grey image per z position,
// and the images themselves (TIFF, PNG, anything OpenImageIO reads; 8 or 16 bit or float).

#include <filesystem>
#include <vector>

#include "imaging/focus_stack.h"

namespace fvm::imaging {

struct FocusStackEntry {
  std::filesystem::path file;  // relative paths in the list are resolved against the list's directory
  double z_mm = 0.0;
  int line = 0;  // in the list, for errors
  std::filesystem::path list{};  // the list that names the image; empty for images named directly
};

// Throws InputError naming the list and line for a missing header, a row without a file or a number, a z that
// repeats or breaks the order (strictly increasing or decreasing), and for fewer than 3 images.
std::vector<FocusStackEntry> ReadFocusStackList(const std::filesystem::path& list);

// One grey image. Colour images are averaged to grey (as float). Throws InputError naming the file when it
// cannot be read.
StackImage ReadStackImage(const std::filesystem::path& path);

// The image as the all-in-focus picture needs it: its first 3 channels (1 for grey files), 8 bit or float
// (16-bit and float files: float in 0..1). Throws InputError naming the file when it cannot be read.
StackImage ReadStackColour(const std::filesystem::path& path);

// The images of a stack named directly rather than by a list: `paths` in focus order, z_mm[i] = i * step_mm.
std::vector<FocusStackEntry> FocusStackFromImages(const std::vector<std::filesystem::path>& paths, double step_mm);

// Written atomically, in the image's own type; the format from the extension (.tif, .png, ...).
void WriteStackImage(const std::filesystem::path& path, const StackImage& image);

}  // namespace fvm::imaging
