#pragma once
// A height map from a focus stack (`fvm focus`): the images (a CSV list with z, a directory, or the files in
// order), aligned when asked, reconstructed with a per-pixel uncertainty and the all-in-focus image, and the
// figures a user reads first.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "imaging/focus_variation.h"
#include "imaging/height_map.h"
#include "imaging/io/focus_stack_files.h"
#include "workflows/summary.h"

namespace fvm::workflows {

// The options as `fvm focus` spells them.
struct FocusOptions {
  std::optional<double> z_step_mm;     // images without z: heights in slice units when not given
  bool align = false;                  // register every image to the first (a macro lens breathes)
  bool keep_end_peaks = false;         // pixels sharpest at an end image take its z
  std::string measure = "laplacian";   // laplacian, tenengrad, variance
  std::string fit = "power";           // sub-step peak interpolation: power, gaussian, parabolic
  int window_px = 0;                   // a fixed focus window (odd, 3 to 51); 0: adaptive
  double min_quality = 2.0;            // peak over mean focus measure below this: invalid
  double pixel_mm = 0.001;             // pixel size on the object
  bool colour = false;                 // the all-in-focus image in colour
  int threads = 0;                     // OpenCV's pool; 0: all cores

  // The reconstruction's options; throws InputError naming --measure, --fit, --window-px, --min-quality or
  // --pixel-mm.
  imaging::FocusVariationOptions Variation() const;
  void Check() const { Variation(); }
};

struct FocusSummary {
  std::vector<imaging::FocusStackEntry> entries;
  imaging::FocusStackFilesResult read;
  imaging::HeightMap map;            // the heights, with its source saying when they are in slice units
  bool slice_units = false;          // no z known: heights count slices
  bool aligned = false;
  imaging::FocusVariationOptions variation;
  imaging::HeightMapStats stats;
  // Medians of the peak quality (every pixel, and the valid ones) and of u_z over the valid pixels; 0 for none.
  double median_quality = 0.0, median_valid_quality = 0.0, median_u = 0.0;
};

// `entries`: imaging::ResolveFocusStack of the stack's files with options.z_step_mm. Throws InputError naming the
// list line or the file, and naming the stack when no pixel has a valid height (nothing to write). `on_image` is
// called after each image (progress).
FocusSummary ReconstructFocus(std::vector<imaging::FocusStackEntry> entries, const FocusOptions& options,
                              const std::function<void()>& on_image = {});

// The figures of a reconstruction made elsewhere (a stack given as arrays): `s.entries`, `s.read`, `s.slice_units`,
// `s.aligned` and `s.variation` set, this fills the map, its statistics and the medians.
void ComputeFocusFigures(FocusSummary& s);

// The --json document {"images", "size_x", ..., "min_quality"} (the command adds "file" first) and the text,
// headed by `output` (the height map's file).
Summary Summarize(const FocusSummary& summary, const std::string& output);

}  // namespace fvm::workflows
