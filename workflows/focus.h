#pragma once
// A height map from a focus stack (`fvm focus`): the images (a CSV list with z, a directory, or the files in
// order), aligned when asked, reconstructed with a per-pixel uncertainty and the all-in-focus image, and the
// figures a user reads first.

#include <filesystem>
#include <optional>
#include <vector>

#include "imaging/focus_variation.h"
#include "imaging/height_map.h"
#include "imaging/io/focus_stack_files.h"

namespace fvm::workflows {

struct FocusOptions {
  imaging::FocusVariationOptions focus;
  std::optional<double> z_step_mm;  // images without z: heights in slice units when not given
  bool align = false;               // register every image to the first (a macro lens breathes)
  bool colour = false;              // the all-in-focus image in colour
  int threads = 0;                  // OpenCV's pool; 0: all cores
};

struct FocusSummary {
  std::vector<imaging::FocusStackEntry> entries;
  imaging::FocusStackFilesResult read;
  imaging::HeightMap map;            // the heights, with its source saying when they are in slice units
  bool slice_units = false;          // no z known: heights count slices
  imaging::HeightMapStats stats;
  // Medians of the peak quality (every pixel, and the valid ones) and of u_z over the valid pixels; 0 for none.
  double median_quality = 0.0, median_valid_quality = 0.0, median_u = 0.0;
};

// `entries`: imaging::ResolveFocusStack of the stack's files with options.z_step_mm. Throws InputError naming the
// list line or the file, and naming the stack when no pixel has a valid height (nothing to write). `on_image` is
// called after each image (progress).
FocusSummary ReconstructFocus(std::vector<imaging::FocusStackEntry> entries, const FocusOptions& options,
                              const std::function<void()>& on_image = {});

}  // namespace fvm::workflows
